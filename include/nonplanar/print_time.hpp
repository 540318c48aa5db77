// How long a G-code program takes to print: Marlin's planner as PrusaSlicer's G-code viewer
// models it (GCodeProcessor's time estimate), so our numbers and its agree. Units: mm, s,
// mm/s, mm/s².
#pragma once

#include <memory>
#include <vector>

#include "nonplanar/program.hpp"

namespace nonplanar {

/// The printer's motion limits (PrusaSlicer's machine_max_* keys, their first, "normal"
/// mode value). Defaults: PrusaSlicer's own. M201, M203, M204 and M205 in the program
/// change them from where they stand, as they change the printer's.
struct MachineLimits {
  double feed_x = 500, feed_y = 500, feed_z = 12, feed_e = 120;           ///< mm/s
  double accel_x = 9000, accel_y = 9000, accel_z = 500, accel_e = 10000;  ///< mm/s²
  double accel_extruding = 1500, accel_retracting = 1500, accel_travel = 1250;
  double jerk_x = 10, jerk_y = 10, jerk_z = 0.2, jerk_e = 2.5;  ///< mm/s
  double min_extruding_rate = 0, min_travel_rate = 0;           ///< mm/s
  /// Marlin 2's junction deviation (machine_max_junction_deviation, M205 J), mm. Above 0 it
  /// replaces the jerk limits at every junction, as in the firmware and PrusaSlicer 2.6+.
  double junction_deviation = 0;
};

struct PrintTime {
  double total = 0;  ///< s, moves and dwells (G4)
  /// Seconds elapsed when each line of the program starts: line_start[i] for lines[i], and
  /// one more entry, the total.
  std::vector<double> line_start;
};

/// Every G0/G1 becomes a block with Marlin's trapezoid: entry speeds bounded by the jerk
/// limits (or the junction deviation) at each junction, then a backward and a forward pass
/// over the blocks queued so each block can reach its neighbours' speeds within its
/// acceleration. As in PrusaSlicer's estimate, once 256 blocks are queued all but the last 64
/// are timed for good.
PrintTime estimate_print_time(const GcodeProgram& program, const MachineLimits& limits);

/// The same estimate fed one line at a time, so a large file need not be held read (a
/// program's lines and moves took 110 MB of the bunny's 23 MB G-code).
class PrintTimer {
 public:
  explicit PrintTimer(const MachineLimits& limits);
  ~PrintTimer();
  PrintTimer(const PrintTimer&) = delete;
  PrintTimer& operator=(const PrintTimer&) = delete;
  /// Room for this many per-line times: one per line, and one for the total (grown by
  /// doubling, they were copied over and over). The moves wait in a queue of at most 257
  /// blocks.
  void reserve(std::size_t lines);
  /// The program's next line, with its move when it is a G0/G1 (else null).
  void line(const GcodeLine& l, const GcodeMove* move);
  /// The estimate of the lines given (line_start: one entry per line, and the total). Once:
  /// the timer hands its memory over and is spent.
  PrintTime finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// "1h 2m 3s", "23m 2s", "45s", as PrusaSlicer writes an estimate.
std::string format_duration(double seconds);

}  // namespace nonplanar
