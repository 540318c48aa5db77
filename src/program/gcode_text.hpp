// The one G-code emitter: every layer the built-in engine writes and every layer of another
// slicer's file mapped back is a ProgramLayer (program.hpp) written here, into a GcodeText, so
// number formats, E bookkeeping (absolute or relative) and the 255-character limit are the
// same on every route. Units: mm, mm of filament, feed rates in mm/min (written as integers).
#pragma once

#include <cmath>
#include <cstdarg>
#include <optional>
#include <string>
#include <string_view>

#include "nonplanar/program.hpp"

namespace nonplanar::program {

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
  /// "G1 X Y Z E F ; comment" with the words `m` asks for: X/Y/Z %.3f of m.to, E %.5f (the
  /// running total in absolute mode), F rounded to an integer.
  void move(const ProgramMove& m);

  void set_e(double e) { e_ = e; }
  void set_relative(bool relative) { rel_e_ = relative; }
  bool relative() const { return rel_e_; }

 private:
  bool rel_e_;
  double e_;
};

/// p as the file holds it: each coordinate rounded to the µm, as move() writes it (%.3f). A
/// writer that derives numbers from positions (E from a segment's length, the first layer's
/// footprint) takes them from here, so they agree with the coordinates written.
inline Vec3 on_file_grid(const Vec3& p) {
  return (p * 1000.0).array().round() / 1000.0;
}

/// vsnprintf into one line of at most 255 characters: false when it does not fit (the line is
/// cut, and the program must be refused with line_too_long()).
bool format_line(char (&buf)[256], const char* fmt, va_list ap)
    __attribute__((format(printf, 2, 0)));
Error line_too_long();

/// Writes one layer's steps, in order, and follows its E changes (a too_long layer sets
/// w.fault).
void write_program_layer(GcodeText& w, const ProgramLayer& layer);

}  // namespace nonplanar::program
