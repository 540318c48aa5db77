// The layer field as text (docs/plan-format.md, "field"), so a plan made by `prepare` can be
// carried in a 3MF and used again by `post-process` to map another slicer's G-code back.
// Units: mm; every number is written so that it reads back to the same double.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "nonplanar/layers.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar {

/// The field as one JSON object: its planar layers and every curved band (top surface,
/// control heights of the stack, faceted top raster, blend raster). Errors: unsupported for
/// a field that is not the pipeline's planar or banded one.
Expected<std::string> layer_field_json(const LayerField& field);

/// Reads what layer_field_json wrote, moved by `shift` in XY (mm): the part was moved on the
/// bed after planning. Every size, count and number is checked (the text may come from any
/// file). Errors: parse_error saying what is wrong.
Expected<std::shared_ptr<const LayerField>> parse_layer_field_json(std::string_view text,
                                                                   const Vec2& shift = {0, 0});

}  // namespace nonplanar
