// Statistics after mapping (#16): time, progress and filament recomputed from the file about
// to be written, so a mapped PrusaSlicer file no longer carries the flattened part's numbers.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "core/huge_pages.hpp"
#include "core/text_tokens.hpp"
#include "nonplanar/gcode.hpp"

namespace nonplanar {
namespace {

// Value n of a profile key ("1000,960": normal and stealth mode), if it is a number; a key
// with fewer values gives its last, as PrusaSlicer's estimator reads it.
std::optional<double> nth_number(const PrintConfig& c, const std::string& key, int n) {
  const auto it = c.profile.find(key);
  if (it == c.profile.end()) return std::nullopt;
  std::string_view v = it->second;
  for (int k = 0; k < n && v.find(',') != std::string_view::npos; ++k)
    v.remove_prefix(v.find(',') + 1);
  const auto d = core::parse_double(v.substr(0, v.find(',')));
  if (!d || !std::isfinite(*d) || *d < 0) return std::nullopt;
  return d;
}

std::optional<double> first_number(const PrintConfig& c, const std::string& key) {
  return nth_number(c, key, 0);
}

// Lines this pass writes itself: the ones an earlier writer left are dropped.
bool is_stat_line(std::string_view l) {
  for (std::string_view p : {"; filament used [", "; total filament used [", "; filament cost =",
                             "; total filament cost =", "; estimated printing time",
                             "; estimated first layer printing time"})
    if (l.substr(0, p.size()) == p) return true;
  return l.size() >= 4 && (l.substr(0, 4) == "M73 " || l == "M73");
}

// "M73 P40 R12": percent done and minutes left ("M73 Q40 S13" for the silent mode).
std::string progress_line(double at, double total, bool silent = false) {
  const int pct = total > 0 ? static_cast<int>(std::floor(100.0 * at / total)) : 100;
  const long left = std::lround(std::max(0.0, total - at) / 60.0);
  char buf[48];
  std::snprintf(buf, sizeof buf, silent ? "M73 Q%d S%ld\n" : "M73 P%d R%ld\n",
                std::clamp(pct, 0, 100), left);
  return buf;
}

}  // namespace

bool silent_mode_estimate(const PrintConfig& c) {
  const auto it = c.profile.find("machine_max_acceleration_x");
  return c.gcode.flavor == GcodeFlavor::marlin2 &&
         first_number(c, "silent_mode").value_or(0) != 0 && it != c.profile.end() &&
         it->second.find(',') != std::string::npos;
}

MachineLimits machine_limits(const PrintConfig& c, int mode) {
  MachineLimits m;
  const std::pair<const char*, double*> keys[] = {
      {"machine_max_feedrate_x", &m.feed_x},
      {"machine_max_feedrate_y", &m.feed_y},
      {"machine_max_feedrate_z", &m.feed_z},
      {"machine_max_feedrate_e", &m.feed_e},
      {"machine_max_acceleration_x", &m.accel_x},
      {"machine_max_acceleration_y", &m.accel_y},
      {"machine_max_acceleration_z", &m.accel_z},
      {"machine_max_acceleration_e", &m.accel_e},
      {"machine_max_acceleration_extruding", &m.accel_extruding},
      {"machine_max_acceleration_retracting", &m.accel_retracting},
      {"machine_max_acceleration_travel", &m.accel_travel},
      {"machine_max_jerk_x", &m.jerk_x},
      {"machine_max_jerk_y", &m.jerk_y},
      {"machine_max_jerk_z", &m.jerk_z},
      {"machine_max_jerk_e", &m.jerk_e},
      {"machine_min_extruding_rate", &m.min_extruding_rate},
      {"machine_min_travel_rate", &m.min_travel_rate},
      {"machine_max_junction_deviation", &m.junction_deviation}};
  for (const auto& [key, field] : keys)
    if (auto v = nth_number(c, key, mode)) *field = *v;
  // PrusaSlicer 2.5 writes a travel acceleration of 0 for "as extruding".
  if (m.accel_travel <= 0) m.accel_travel = m.accel_extruding;
  return m;
}

PrintStats print_stats(const GcodeProgram& program, const PrintConfig& c, PrintTime* time) {
  PrintTime t = estimate_print_time(program, machine_limits(c));
  double filament = 0;  // net: a retraction and its restore cancel
  for (const GcodeMove& m : program.moves) filament += m.de;
  filament = std::max(0.0, filament);
  const double d = c.gcode.filament_diameter;
  const double cm3 = filament * M_PI * 0.25 * d * d / 1000.0;
  const double grams = cm3 * first_number(c, "filament_density").value_or(0);
  PrintStats s{t.total, filament, cm3, grams};
  if (time) *time = std::move(t);
  return s;
}

PrintStatsStamp measure_print_stats(std::string_view gcode, const PrintConfig& c) {
  // Read once, streamed: the time (and the MK3S's stealth mode's, PrusaSlicer's "silent
  // mode": its own estimate and progress) and the net E of every move.
  PrintStatsStamp m;
  m.silent = silent_mode_estimate(c);
  m.progress = first_number(c, "remaining_times").value_or(0) != 0;
  PrintTimer normal(machine_limits(c)), stealth(machine_limits(c, m.silent ? 1 : 0));
  const GcodeLineCount n = count_gcode_lines(gcode);  // and one entry more: the total
  normal.reserve(n.lines + 1);
  if (m.silent) stealth.reserve(n.lines + 1);
  double filament = 0;  // net: a retraction and its restore cancel
  m.print_end = for_each_gcode_line(gcode, [&](const GcodeLine& l, const GcodeMove* mv) {
                  normal.line(l, mv);
                  if (m.silent) stealth.line(l, mv);
                  if (mv) filament += mv->de;
                }).print_end;
  m.normal = normal.finish();
  if (m.silent) m.stealth = stealth.finish();
  filament = std::max(0.0, filament);
  const double d = c.gcode.filament_diameter;
  const double cm3 = filament * M_PI * 0.25 * d * d / 1000.0;
  const double grams = cm3 * first_number(c, "filament_density").value_or(0);
  m.stats = PrintStats{m.normal.total, filament, cm3, grams};
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "; filament used [mm] = %.2f\n; filament used [cm3] = %.2f\n"
                "; filament used [g] = %.2f\n",
                filament, cm3, grams);
  m.footer = buf;
  if (const auto cost_per_kg = first_number(c, "filament_cost")) {
    std::snprintf(buf, sizeof buf, "; filament cost = %.2f\n", grams / 1000.0 * *cost_per_kg);
    m.footer += buf;
  }
  m.footer += "; estimated printing time (normal mode) = " + format_duration(m.normal.total) + "\n";
  if (m.silent)
    m.footer +=
        "; estimated printing time (silent mode) = " + format_duration(m.stealth.total) + "\n";
  return m;
}

void stamp_print_stats(std::string& gcode, const PrintStatsStamp& m) {
  // In place, in two sweeps, so a 40 MB program is never held twice: forward, the lines are
  // moved down over the dropped ones (old stats lines, CRs), noting where text goes in; then
  // backward, each stretch moves up by what goes in before it.
  if (!gcode.empty() && gcode.back() != '\n') gcode += '\n';  // the last line ends too
  std::vector<std::pair<std::size_t, std::string>> inserts;   // at a place of the moved text
  std::size_t w = 0;
  auto progress_at = [&](std::size_t i) {
    return progress_line(m.normal.line_start[i], m.normal.total) +
           (m.silent ? progress_line(m.stealth.line_start[i], m.stealth.total, true) : "");
  };
  bool placed = false, finished = false;
  auto finish = [&] {  // 100 % once the print is done, before the footer at the latest
    if (!m.progress || finished) return;
    inserts.emplace_back(w, progress_line(1, 1) + (m.silent ? progress_line(1, 1, true) : ""));
    finished = true;
  };
  auto place = [&] {
    finish();
    if (!placed) inserts.emplace_back(w, m.footer), placed = true;
  };
  if (m.progress) inserts.emplace_back(0, progress_at(0));  // first, as PrusaSlicer writes it
  std::size_t i = 0;
  for (std::size_t start = 0; start < gcode.size(); ++i) {
    const std::size_t end = gcode.find('\n', start);
    std::string_view l(gcode.data() + start, end - start);
    start = end + 1;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    if (l == "; prusaslicer_config = begin") place();
    if (is_stat_line(l)) {
      if (l.rfind("; ", 0) == 0) place();
      continue;
    }
    if (m.progress && l == ";LAYER_CHANGE") inserts.emplace_back(w, progress_at(i));
    if (i == m.print_end) finish();
    std::memmove(gcode.data() + w, l.data(), l.size());  // never ahead of where it was read
    w += l.size();
    gcode[w++] = '\n';
  }
  place();
  std::size_t grow = 0;
  for (const auto& ins : inserts) grow += ins.second.size();
  gcode.resize(w + grow);
  std::size_t tail = w;  // the moved text from here on is in place already
  for (std::size_t k = inserts.size(); k-- > 0;) {
    const auto& [at, text] = inserts[k];
    grow -= text.size();
    std::memmove(gcode.data() + at + grow + text.size(), gcode.data() + at, tail - at);
    std::memcpy(gcode.data() + at + grow, text.data(), text.size());
    tail = at;
  }
}

std::string with_print_stats(std::string_view gcode, const PrintConfig& c, PrintStats* stats) {
  const PrintStatsStamp m = measure_print_stats(gcode, c);
  std::string out;
  out.reserve(gcode.size() + gcode.size() / 50 + m.footer.size() + 1);
  advise_huge_pages(out.data(), out.capacity());
  out.assign(gcode);
  stamp_print_stats(out, m);
  if (stats) *stats = m.stats;
  return out;
}

}  // namespace nonplanar
