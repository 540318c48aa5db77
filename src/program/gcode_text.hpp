// The one G-code emitter: every G1 the built-in engine writes and every line of another
// slicer's file mapped back go through GcodeText, so number formats, E bookkeeping (absolute
// or relative) and the 255-character limit are the same on every route. Units: mm, mm of
// filament, feed rates in mm/min (written as integers).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "nonplanar/program.hpp"

namespace nonplanar::program {

/// The words of one G1 line besides the position.
struct MoveWords {
  bool xy = false, z = false;     ///< write X Y, write Z
  double de = kNoValue;           ///< filament pushed, mm (kNoValue: no E word)
  double f = kNoValue;            ///< feed rate, mm/min (kNoValue: no F word)
  const char* comment = nullptr;  ///< written after " ; "
};

class GcodeText {
 public:
  explicit GcodeText(bool relative_e = false, double e = 0) : rel_e_(relative_e), e_(e) {}
  std::string out;
  /// The first line too long to format (a number out of any printer's range): set, and the
  /// program must be refused.
  std::optional<Error> fault;

  /// One line as given, and its line end.
  void raw(std::string_view line) {
    out.append(line);
    out.push_back('\n');
  }
  /// Lines already ended (a custom G-code block).
  void block(std::string_view text) { out.append(text); }
  /// printf into one line (at most 255 characters, else `fault`).
  void line(const char* fmt, ...) __attribute__((format(printf, 2, 3)));
  /// "G1 X Y Z E F ; comment" with the words `w` asks for: X/Y/Z %.3f of p, E %.5f (the
  /// running total in absolute mode), F rounded to an integer.
  void move(const Vec3& p, const MoveWords& w);
  /// A move from `from` to p that writes only the axes that change by more than 0.5 µm
  /// (what %.3f can show), E and F where given; nothing when no word is left.
  void move_from(const Vec3& from, const Vec3& p, double de, double f);

  void set_e(double e) { e_ = e; }
  void set_relative(bool relative) { rel_e_ = relative; }
  bool relative() const { return rel_e_; }

 private:
  bool rel_e_;
  double e_;
};

/// A travel that clears a curved layer: up to `lift` where the nozzle is (at), across at that
/// height, down to `to` (pushing `de` there, if given: a retraction given back). `f_first` on
/// the first line, `f_rest` on the others (kNoValue: none, the feed rate stays in force).
/// travel_height (toolhead.hpp) says how high.
void lifted_travel(GcodeText& w, const Vec3& at, const Vec3& to, double lift, double f_first,
                   double f_rest, double de = kNoValue);

}  // namespace nonplanar::program
