// order_top_skins (layer_passes.hpp): a run of top solid infill, its strokes printed low to
// high, each from its low end.
#include <algorithm>
#include <cmath>

#include "program/layer_passes.hpp"

namespace nonplanar::program {

GcodeLine LayerWork::add(GcodeMove m, ExtrusionPath p) {
  moves.push_back(std::move(m));
  mapped.push_back(std::move(p));
  GcodeLine it;
  it.kind = GcodeLine::Kind::move;
  it.move = static_cast<int>(moves.size()) - 1;
  return it;
}

LowToHigh low_to_high(const std::vector<StrokeHeights>& strokes, const Toolhead& head) {
  LowToHigh r;
  const std::size_t n = strokes.size();
  r.order.resize(n);
  r.reverse.resize(n);
  std::vector<ReachBox> boxes(n);
  for (std::size_t i = 0; i < n; ++i) {
    r.order[i] = i, r.reverse[i] = strokes[i].first > strokes[i].last + 1e-9;
    boxes[i] = strokes[i].box;
  }
  std::stable_sort(r.order.begin(), r.order.end(),
                   [&](std::size_t a, std::size_t b) { return strokes[a].mean < strokes[b].mean; });
  const std::vector<std::size_t> group = reach_groups(boxes, head);
  std::vector<std::size_t> rank(n, n);  // each group's place: by its lowest stroke
  std::size_t groups = 0;
  for (std::size_t k : r.order)
    if (rank[group[k]] == n) rank[group[k]] = groups++;
  if (groups > 1)
    std::stable_sort(r.order.begin(), r.order.end(),
                     [&](std::size_t a, std::size_t b) { return rank[group[a]] < rank[group[b]]; });
  return r;
}

namespace {

using Kind = GcodeLine::Kind;

// One run of top solid infill: its strokes (indices of moves), its other lines before the
// last stroke (head) and after it (tail), and the feed rates and retraction it used.
struct Run {
  std::vector<std::vector<int>> strokes;
  std::vector<GcodeLine> head, tail;
  double ret = 0, ret_f = kNoValue, unret_f = kNoValue, travel_f = kNoValue, print_f = kNoValue;
};

bool is_type(const GcodeLine& it, std::string_view t) {
  return it.kind == Kind::text && it.raw.rfind(t, 0) == 0;
}

// Lines [s + 1, e) of the layer, sorted into a Run.
Run collect_run(LayerWork& w, std::size_t s, std::size_t e) {
  Run r;
  std::size_t last = s;
  for (std::size_t k = s + 1; k < e; ++k)
    if (w.lines[k].kind == Kind::move &&
        w.moves[static_cast<std::size_t>(w.lines[k].move)].extruding())
      last = k;
  bool in_stroke = false;
  for (std::size_t k = s + 1; k < e; ++k) {
    const GcodeLine it = w.lines[k];
    if (k > last) {
      GcodeMove m =
          it.kind == Kind::move ? w.moves[static_cast<std::size_t>(it.move)] : GcodeMove{};
      if (it.kind == Kind::move && m.wipe && m.has_xy) {  // a wipe: its retraction, in place
        m.has_xy = false, m.to = m.from;
        r.tail.push_back(w.add(std::move(m)));
      } else {
        r.tail.push_back(it);
      }
      continue;
    }
    if (it.kind != Kind::move) {
      if (it.kind != Kind::e_reset) r.head.push_back(it);  // E is ours inside the run
      continue;
    }
    const GcodeMove& m = w.moves[static_cast<std::size_t>(it.move)];
    if (m.extruding()) {
      if (!in_stroke) r.strokes.emplace_back();
      r.strokes.back().push_back(it.move);
      in_stroke = true;
      continue;
    }
    in_stroke = false;
    const bool e_only = !m.has_xy && !m.has_z;
    if (e_only && m.has_e && m.de < 0 && r.ret == 0) r.ret = -m.de, r.ret_f = m.f;
    if (e_only && m.has_e && m.de > 0 && std::isnan(r.unret_f)) r.unret_f = m.f;
    if (e_only && !m.has_e && !std::isnan(m.f) && r.strokes.empty()) r.print_f = m.f;
    if (m.has_xy && !m.has_e && std::isnan(r.travel_f)) r.travel_f = m.f;
  }
  return r;
}

// The travel from prev to the start of `stroke` (low end first), retracted around when over
// retract_over, then the stroke; appended to out. Returns where the stroke ends.
Vec3 write_stroke(LayerWork& w, const Run& r, const std::vector<int>& stroke, bool reverse,
                  const Vec3& prev, double retract_over, std::vector<GcodeLine>& out) {
  GcodeMove travel = w.moves[static_cast<std::size_t>(reverse ? stroke.back() : stroke.front())];
  const Vec3 start = reverse ? travel.to : travel.from;
  travel.from = prev, travel.to = start, travel.has_xy = true, travel.has_z = false;
  travel.has_e = false, travel.de = 0, travel.wipe = false, travel.f = r.travel_f;
  GcodeMove back = travel;
  back.has_xy = false, back.from = back.to = prev, back.has_e = true, back.de = -r.ret;
  back.f = r.ret_f;
  const bool hop = r.ret > 0 && (start - prev).head<2>().norm() > retract_over;
  if (hop) out.push_back(w.add(back));
  out.push_back(w.add(travel));
  if (hop) {
    back.from = back.to = start, back.de = r.ret, back.f = r.unret_f;
    out.push_back(w.add(back));
  }
  Vec3 end = start;
  for (std::size_t q = 0; q < stroke.size(); ++q) {
    const int idx = stroke[reverse ? stroke.size() - 1 - q : q];
    GcodeMove m = w.moves[static_cast<std::size_t>(idx)];
    ExtrusionPath p = w.mapped[static_cast<std::size_t>(idx)];
    if (reverse) {
      std::swap(m.from, m.to);
      std::reverse(p.points.begin(), p.points.end());
      std::reverse(p.height.begin(), p.height.end());
    }
    if (q == 0 && std::isnan(m.f)) m.f = r.print_f;
    end = m.to;
    out.push_back(w.add(std::move(m), std::move(p)));
  }
  return end;
}

}  // namespace

void order_top_skins(LayerWork& w, const LayerPassParams& params) {
  auto heights = [&](const std::vector<int>& stroke) {
    StrokeHeights h;
    std::size_t n = 0;
    for (int m : stroke) {
      const ExtrusionPath& p = w.mapped[static_cast<std::size_t>(m)];
      for (const Vec3& v : p.points) h.mean += v.z(), h.box.extend(v), ++n;
      h.box.width = std::max(h.box.width, p.width);
    }
    h.mean = n ? h.mean / static_cast<double>(n) : 0.0;
    h.first = w.mapped[static_cast<std::size_t>(stroke.front())].points.front().z();
    h.last = w.mapped[static_cast<std::size_t>(stroke.back())].points.back().z();
    return h;
  };
  std::vector<GcodeLine>& seq = w.lines;
  for (std::size_t s = 0; s < seq.size(); ++s) {
    if (!is_type(seq[s], ";TYPE:Top solid infill")) continue;
    std::size_t e = s + 1;
    while (e < seq.size() && !is_type(seq[e], ";TYPE:")) ++e;
    Run r = collect_run(w, s, e);
    if (r.strokes.empty()) continue;
    std::vector<StrokeHeights> h;
    for (const auto& stroke : r.strokes) h.push_back(heights(stroke));
    const LowToHigh order = low_to_high(h, params.head);
    std::vector<GcodeLine> out{seq[s]};
    out.insert(out.end(), r.head.begin(), r.head.end());
    Vec3 prev = w.moves[static_cast<std::size_t>(r.strokes[order.order[0]].front())].from;
    for (std::size_t k : order.order)
      prev = write_stroke(w, r, r.strokes[k], order.reverse[k] != 0, prev, params.skin_retract_over,
                          out);
    out.insert(out.end(), r.tail.begin(), r.tail.end());
    seq.erase(seq.begin() + static_cast<long>(s), seq.begin() + static_cast<long>(e));
    seq.insert(seq.begin() + static_cast<long>(s), out.begin(), out.end());
    s += out.size() - 1;
  }
}

}  // namespace nonplanar::program
