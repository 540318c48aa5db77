// clip_layer (layer_passes.hpp): a planar layer cut back to where a margin is >= 0 (the
// shell's core under the shell), and what is left of a layer cut away whole (dropped_layer).
// s is the parameter along a move, 0 at its start, 1 at its end.
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "program/layer_passes.hpp"

namespace nonplanar::program {
namespace {

// The pieces of the move from a to b (length len in XY) on either side of margin g(s) = 0:
// cut parameters 0 = s_0 < … < s_n = 1 and, for each piece, whether it is kept.
struct Pieces {
  std::vector<double> cuts;
  std::vector<char> kept;
};

// g is looked at on n steps, and each step where its sign changes is bisected. With |∇g| at
// most `slope` along the move, the steps within (|g| − 1 µm) / (slope · len / n) of one are
// skipped: their signs are its own.
template <class G>
Pieces cut_move(const G& g_at, double len, int n, double slope, std::size_t& samples) {
  auto g = [&](double s) { return ++samples, g_at(s); };
  const double per_step = slope * len / n;
  double s0 = 0, g0 = g(0);
  // Farther from 0 than the move can change it: all of it on g0's side, looked at once (most
  // moves of a core cut only round a shell's region).
  if ((std::abs(g0) - 1e-6) / per_step >= n) return Pieces{{0.0, 1.0}, {g0 >= 0}};
  std::vector<double> cuts{0.0};
  for (int k = 1; k <= n; ++k) {
    const double room = (std::abs(g0) - 1e-6) / per_step;  // NaN or under 1: no step skipped
    if (room >= 1) k = static_cast<int>(std::min(room + (k - 1), static_cast<double>(n)));
    const double s1 = static_cast<double>(k) / n, g1 = g(s1);
    if ((g0 >= 0) != (g1 >= 0)) {
      double lo = s0, hi = s1;
      for (int b = 0; b < 30; ++b) {
        const double mid = 0.5 * (lo + hi);
        ((g(mid) >= 0) == (g0 >= 0) ? lo : hi) = mid;
      }
      cuts.push_back(0.5 * (lo + hi));
    }
    s0 = s1, g0 = g1;
  }
  cuts.push_back(1.0);
  // Neighbouring pieces on the same side are one, and a piece under 1 µm takes its
  // neighbour's side: a margin of exactly 0 (a flat floor the core's boundaries were
  // snapped to) flips back and forth within a step, or touches 0 at one point.
  Pieces p;
  p.cuts.push_back(0.0);
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    const bool sliver = k > 0 && (cuts[k + 1] - cuts[k]) * len < 1e-3;
    const char in = sliver ? p.kept.back() : g(0.5 * (cuts[k] + cuts[k + 1])) >= 0;
    if (k > 0 && in != p.kept.back()) p.cuts.push_back(cuts[k]);
    if (k == 0 || in != p.kept.back()) p.kept.push_back(in);
  }
  p.cuts.push_back(1.0);
  return p;
}

}  // namespace

namespace {

// Whether clip_layer cuts the move of line `it`: an extrusion not left `untouched`.
bool cut_here(const LayerWork& w, const GcodeLine& it,
              const std::function<bool(const GcodeMove&)>& untouched) {
  if (it.kind != GcodeLine::Kind::move) return false;
  const GcodeMove& m = w.moves[static_cast<std::size_t>(it.move)];
  return m.extruding() && !(untouched && untouched(m));
}

}  // namespace

LayerCuts cut_layer(const LayerWork& w, const std::function<double(double, double)>& margin,
                    const std::function<double(const Vec2&, const Vec2&)>& slope_bound,
                    const LayerPassParams& params, std::atomic<std::size_t>& looked,
                    const std::function<bool(const GcodeMove&)>& untouched) {
  LayerCuts out;
  out.complete = true;
  for (const GcodeLine& it : w.lines) {
    if (!cut_here(w, it, untouched)) continue;
    const GcodeMove& m = w.moves[static_cast<std::size_t>(it.move)];
    auto g = [&](double s) {
      const Vec3 p = m.from + s * (m.to - m.from);
      return margin(p.x(), p.y());
    };
    const double len = (m.to - m.from).head<2>().norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / params.clip_step)));
    out.steps.push_back(static_cast<std::uint32_t>(n));
    if (looked.load(std::memory_order_relaxed) + static_cast<std::size_t>(n) >
        params.most_clip_samples) {
      out.looks.push_back(0), out.complete = false;
      return out;
    }
    // On the wing's core 7 in 10 moves lie wholly on one side, clear of the cut, and a long
    // infill line across it is looked at step by step only near it: the core's mapping took
    // 0.61 s, now 0.10 s.
    const double slope = slope_bound ? slope_bound(m.from.head<2>().cwiseMin(m.to.head<2>()),
                                                   m.from.head<2>().cwiseMax(m.to.head<2>()))
                                     : std::numeric_limits<double>::infinity();
    std::size_t samples = 0;
    Pieces pieces = cut_move(g, len, n, slope, samples);
    out.looks.push_back(static_cast<std::uint32_t>(std::min<std::size_t>(samples, UINT32_MAX)));
    out.cuts.insert(out.cuts.end(), pieces.cuts.begin(), pieces.cuts.end());
    out.kept.insert(out.kept.end(), pieces.kept.begin(), pieces.kept.end());
    out.begin.push_back(static_cast<std::uint32_t>(out.cuts.size()));
    if (looked.fetch_add(samples, std::memory_order_relaxed) + samples > params.most_clip_samples) {
      out.complete = false;
      return out;
    }
  }
  return out;
}

int clip_layer(LayerWork& w, const LayerCuts& cuts, const GcodeRetraction& ret,
               const LayerPassParams& params, std::size_t& samples,
               const std::function<bool(const GcodeMove&)>& untouched) {
  std::vector<GcodeLine> out;
  out.reserve(w.lines.size());
  // The give-back of a retraction around cut-away travel: held while the travel goes on (the
  // next extrusion cut away too, as a whole perimeter above the core often is), added before
  // anything else.
  std::optional<GcodeMove> owed;
  auto settle = [&] {
    if (owed) out.push_back(w.add(*owed)), owed.reset();
  };
  std::size_t k = 0;  // the cut move's index in `cuts`
  for (const GcodeLine& it : w.lines) {
    if (!cut_here(w, it, untouched)) {
      settle();
      out.push_back(it);
      continue;
    }
    const GcodeMove m = w.moves[static_cast<std::size_t>(it.move)];
    // The count as the moves were cut one by one: the line it passes the limit on.
    if (k >= cuts.steps.size() || samples + cuts.steps[k] > params.most_clip_samples) return m.line;
    samples += cuts.looks[k];
    if (samples > params.most_clip_samples || k + 1 >= cuts.begin.size()) return m.line;
    const std::size_t b = cuts.begin[k], e = cuts.begin[k + 1], kept0 = b - k;
    ++k;
    if (e - b == 2 && cuts.kept[kept0]) {
      out.push_back(it);
      continue;
    }
    auto at = [&](double s) { return Vec3(m.from + s * (m.to - m.from)); };
    for (std::size_t q = b; q + 1 < e; ++q) {
      GcodeMove piece = m;
      piece.from = at(cuts.cuts[q]), piece.to = at(cuts.cuts[q + 1]);
      piece.f = q == b ? m.f : kNoValue;
      if (cuts.kept[kept0 + (q - b)]) {
        if (owed) settle(), piece.f = m.feed;  // after the give-back's feed rate
        piece.de = m.de * (cuts.cuts[q + 1] - cuts.cuts[q]);
        out.push_back(w.add(piece));
        continue;
      }
      piece.de = 0, piece.has_e = false;
      const bool hop = ret.length > 0 && (owed || (piece.to - piece.from).head<2>().norm() >
                                                      params.clip_retract_over);
      GcodeMove r = piece;
      r.has_xy = false, r.has_e = true;
      if (hop && !owed) {
        r.to = r.from, r.de = -ret.length, r.f = ret.f;
        out.push_back(w.add(r));
      }
      if (hop) piece.f = m.feed;
      out.push_back(w.add(piece));
      if (hop) r.from = r.to = piece.to, r.de = ret.length, r.f = ret.back_f, owed = r;
    }
  }
  settle();
  w.lines = std::move(out);
  return 0;
}

int clip_layer(LayerWork& w, const std::function<double(double, double)>& margin,
               const std::function<double(const Vec2&, const Vec2&)>& slope_bound,
               const GcodeRetraction& ret, const LayerPassParams& params, std::size_t& samples,
               const std::function<bool(const GcodeMove&)>& untouched) {
  std::atomic<std::size_t> looked{samples};
  const LayerCuts cuts = cut_layer(w, margin, slope_bound, params, looked, untouched);
  return clip_layer(w, cuts, ret, params, samples, untouched);
}

void dropped_layer(const std::vector<GcodeLine>& lines, ProgramLayer& out) {
  for (const GcodeLine& it : lines)
    if (it.kind == GcodeLine::Kind::text || it.kind == GcodeLine::Kind::e_mode)
      if (!it.raw.empty() && std::toupper(static_cast<unsigned char>(it.raw[0])) == 'M' &&
          it.raw.rfind("M106", 0) != 0 && it.raw.rfind("M107", 0) != 0) {
        if (it.kind == GcodeLine::Kind::e_mode)
          out.e_mode(it.raw, it.value != 0);
        else
          out.raw(it.raw);
      }
}

}  // namespace nonplanar::program
