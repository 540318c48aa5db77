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
/// field's bands when the part has curved stacks (collisions are then looked for only near
/// them: gate_zones.hpp; null: everywhere). Checks thickness within [h_min, h_max] and slope
/// within max_angle + 0.5° on the paths themselves, rounded first to the µm they are written
/// with, and collisions with earlier layers through check's collision search. Every breach
/// goes to `violation`. Output: false when `violation` said stop; fills r's figures.
/// Errors: cancelled.
Expected<bool> gate(SliceResult& r, const SliceJob& job, const layers::BandedField* banded,
                    const Violation& violation, const Context& ctx);

/// The same moves straight from toolpaths (the gate's input, as the written file will hold them);
/// when `keep` is given, only the paths it accepts, called with each path and its layer (the travel
/// to the next kept path starts where the last kept one ended).
std::vector<PrintMove> moves_from_toolpaths(
    const std::vector<LayerToolpaths>& layers, const GcodeParams& g,
    const std::function<bool(const ExtrusionPath&, int layer)>& keep = nullptr);

/// A part thinner than one extrusion, or an open sheet, slices to nothing: the error that
/// says so (invalid_mesh, with the part's size), or nothing when r prints something.
std::optional<Error> nothing_to_print(const SliceResult& r, const TriangleMesh& mesh);

}  // namespace nonplanar
