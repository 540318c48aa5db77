// Some lines of a G-code file, written as a program of their own: what a printer needs between
// two kept lines that the dropped ones in between had set (a shell route's core without the
// shell's layers, its shell without the other objects on the plate).
//
// The state a printer carries from line to line: E (absolute mode: its value; both modes: how
// much filament is pulled back), where the head is, the feed rate, the E mode and the fan.
// Before each kept move the spliced text is brought to the state the file had there: M82/M83,
// G92 E, a retraction or its give-back (a retraction before a travel, the give-back after it),
// a travel to where the file's head was (before an extrusion, retracted around with the
// file's own retraction when over 2 mm; its Z, before a travel that writes none), the feed rate
// (before a move without F), the fan (before an extrusion). So a kept extrusion lays what it laid
// in the file, where it laid it. A wipe that would retrace an extrusion the text lacks pulls its
// filament back where the head is instead.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/program.hpp"

namespace nonplanar::program {

class LineSplicer {
 public:
  /// `prog` (read_gcode_program) and the text it views outlive the splicer. The file's
  /// retraction feed rate (prog.retraction) writes the retractions it adds (2100 mm/min when
  /// the file has none).
  explicit LineSplicer(const GcodeProgram& prog);

  /// Appends lines [begin, end) (0-based, begin no lower than the last call's end) to `out`:
  /// those with keep[i] != 0, each with a line end, after what brings the printer to the
  /// file's state there; the rest are followed, not written. `marks`, when given, gets one
  /// entry per line written to `out`: keep[i] for a kept line, 0 for an added one.
  void append(std::size_t begin, std::size_t end, const std::vector<char>& keep, std::string& out,
              std::vector<char>* marks = nullptr);

  /// A refusal found on the way (a G91 among the print's lines followed, under which the
  /// travels it adds would go wrong; the start and end G-code's own are theirs); empty when
  /// none.
  const std::string& problem() const { return problem_; }

 private:
  struct State {
    double e = 0;          ///< absolute E (absolute mode), mm
    double retracted = 0;  ///< filament pulled back by non-extruding moves since the start, mm
    Vec3 at{0, 0, 0};
    double feed = kNoValue;
    bool relative_e = false;
    std::string_view fan;  ///< the last M106/M107 line ("" when none)
  };
  /// The file's state after line i (all lines) or the text's (kept lines).
  void follow(const GcodeLine& l, State& s) const;
  /// What brings the text to the file's state before the kept move m.
  void reconcile(const GcodeMove& m, std::string& out, std::vector<char>* marks);
  void add(std::string& out, std::vector<char>* marks, const char* fmt, ...)
      __attribute__((format(printf, 4, 5)));

  const GcodeProgram& prog_;
  std::size_t next_ = 0;
  State file_, text_state_;
  double retract_f_ = 2100;
  std::string problem_;
};

}  // namespace nonplanar::program
