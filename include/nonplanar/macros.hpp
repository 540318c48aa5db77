// PrusaSlicer's placeholder language, for custom G-code blocks (start_gcode, end_gcode,
// before_layer_gcode, layer_gcode, start/end_filament_gcode):
//   [var], [var[index_var]]            legacy expansion (a vector gives its first value)
//   {expr}                              an expression's value
//   {if expr}…{elsif expr}…{else}…{endif}
// Expressions: numbers, "strings", true/false, var, var[expr], + - * / %, == != <> < > <= >=,
// =~ /regex/ and !~ /regex/ (whole-string match), and/&&, or/||, not/!, c ? a : b, and
// min, max, int, round, digits, zdigits. Integers stay integers (7/2 is 3) as in PrusaSlicer,
// and a real prints as C++ streams print it (%g). Anything that cannot be evaluated is an
// error naming the block and the line: nothing is ever sent to the printer unexpanded.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar {

/// One value of the language.
struct MacroValue {
  enum class Type { boolean, integer, real, text };
  Type type = Type::integer;
  bool b = false;
  long long i = 0;
  double d = 0;
  std::string s;
  static MacroValue boolean(bool v) { return {Type::boolean, v, 0, 0, {}}; }
  static MacroValue integer(long long v) { return {Type::integer, false, v, 0, {}}; }
  static MacroValue real(double v) { return {Type::real, false, 0, v, {}}; }
  static MacroValue text(std::string v) { return {Type::text, false, 0, 0, std::move(v)}; }
};

/// The variables a block sees: the profile's keys and what the writer knows at that point
/// of the print (max_layer_z, layer_num, first_layer_print_min, …).
class MacroVariables {
 public:
  void set(const std::string& name, MacroValue v) { vars_[name] = {std::move(v)}; }
  void set_vector(const std::string& name, std::vector<MacroValue> v) {
    vars_[name] = std::move(v);
  }
  /// A profile's key = value as written in a PrusaSlicer .ini (escapes intact): "0.4,0.4" is a
  /// vector of reals, "215" an integer, "\"a\";\"b\"" a vector of strings, anything else a
  /// string with its \n escapes undone.
  void set_from_profile(const std::string& key, const std::string& raw);
  /// nullptr when there is no such variable.
  const std::vector<MacroValue>* find(std::string_view name) const;

 private:
  std::map<std::string, std::vector<MacroValue>, std::less<>> vars_;
};

/// Expands `text` (the block named `block`, for errors). Error (invalid_argument):
/// "BLOCK: line N: problem", e.g. "end_gcode: line 1: 'max_layer_zz' is not a variable".
Expected<std::string> expand_macros(std::string_view text, const MacroVariables& vars,
                                    const std::string& block);

/// The variables a profile's macros see before printing: PrusaSlicer's defaults for keys a
/// profile may leave out (printer_model "", filament_type "PLA", ...), every key of
/// `c.profile`, the values we resolved from them (layer_height, temperature[0], the
/// widths), and the bed (print_bed_min/max/size). The writer adds the print's facts.
MacroVariables profile_variables(const PrintConfig& c);

}  // namespace nonplanar
