// The safety gate (DESIGN.md §3): nothing is written that breaks a printer limit.
#pragma once

#include <functional>
#include <optional>

#include "layers/banded_field.hpp"
#include "nonplanar/pipeline.hpp"

namespace nonplanar {

/// Called with where a limit is broken and which; returns false to stop looking.
using Violation = std::function<bool(const Vec3&, const char*)>;

/// Inputs: the result about to be written (its layers), the job's limits and toolhead, the
/// field's bands when the part has curved stacks (collisions and crossings are then looked for
/// only near them: gate_zones.hpp; null: everywhere). Checks thickness within [h_min, h_max]
/// on the paths' heights, then, in the program about to be written (r.gcode, made here by
/// write_program when empty) read back by the one reader: slope within max_angle, and where a
/// curved layer's line crosses the material under it, a thickness of at least h_min (check's
/// LayerGaps), both with job.gate's slack; and, when something is curved, collisions with
/// earlier layers, searched by check's own collision search. Every breach goes to
/// `violation`. Output: false when `violation` said stop; fills r's figures (the thickness
/// ones LayerGaps'). Errors: those of write_program, cancelled.
Expected<bool> gate(SliceResult& r, const SliceJob& job, const layers::BandedField* banded,
                    const Violation& violation, const Context& ctx);

/// r.gcode, the whole program, made by the built-in writer from r.layers when no engine wrote
/// it (its header: r.header, then job.header). Errors: what make_gcode refuses (a move off the
/// bed, custom G-code it cannot fill in), cancelled.
Expected<void> write_program(SliceResult& r, const SliceJob& job, const Context& ctx);

/// A part thinner than one extrusion, or an open sheet, slices to nothing: the error that
/// says so (invalid_mesh, with the part's size), or nothing when r prints something.
std::optional<Error> nothing_to_print(const SliceResult& r, const TriangleMesh& mesh);

}  // namespace nonplanar
