// Where the G-code of a shell's stack splits (ShellStack in shell_engine.hpp: what prepare
// writes for the user's slicer and the engine route gives PrusaSlicer): the planned part's
// core, in layers with tops on the plan's boundaries up to z_s; its layer z_s … z_s + t that
// held the shell's slab up (dropped); its shell's layers, t thick. Other objects on the plate
// print with the core, as the slicer wrote them.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "layers/shell_plan.hpp"
#include "nonplanar/program.hpp"

namespace nonplanar {

/// Whose each line of a program is, by the slicer's object labels: 0 outside every label
/// (layer changes), 1 the planned part's, 2 another object's.
enum LineOwner : char { kUnlabelled = 0, kOurs = 1, kOthers = 2 };

struct ShellSplit {
  layers::ShellPlan plan;  ///< the plan's shell, where the part was placed
  /// The file without the planned part's lines above z_s (the layers only it prints there go
  /// whole), as a program of its own (program/splice_lines.hpp).
  std::string core;
  /// Per line of `core`: 1 where another object's (kept as written), else 0.
  std::vector<char> others;
  /// The file's start G-code, then the layers of the shell (the planned part's lines and
  /// the layer changes), then its end G-code; a program of its own.
  std::string shell;
  /// Whether other objects share the plate (they print with the core, the shell after them).
  bool shares_plate = false;
  /// Support extrusions the slicer put in the shell's layers (under the slab, which stands
  /// above the part in the 3MF; a support blocker keeps them off), left out; mm of them.
  double supports_left_out = 0;
};

/// Inputs: the file read (`prog` from `gcode`), whose each line is (size = prog.lines; empty:
/// every line the part's), the shell's plan (where the part was placed). Output: the split;
/// refused (invalid_argument, one line) when the part's layers above z_s are not the plan's
/// (no layer ends at z_s + t, a shell layer off the t grid) or the shell's layers hold nothing
/// but supports.
Expected<ShellSplit> shell_split(const GcodeProgram& prog, std::string_view gcode,
                                 std::vector<char> owner, layers::ShellPlan plan);

}  // namespace nonplanar
