// One layer of another slicer's planar G-code mapped onto the curved layers (notation as in
// map_segment.hpp): its extrusions and wipes resampled into `mapped`, indexed like the moves.
// Used a layer at a time by map_foreign_gcode, or for many layers side by side when nothing
// is clipped (the layers are then independent).
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "nonplanar/deform.hpp"
#include "program/layer_passes.hpp"

namespace nonplanar {

/// Is m a move planar_lines (by 0-based file line; 1: keep) leaves where the file has it?
bool kept_planar(const std::vector<char>& planar_lines, const GcodeMove& m);

/// Inputs: a layer's lines, the program's moves (lines[k].move indexes them), the field,
/// params (tolerance, most_points), planar_lines (moves left where the file has them, by
/// 0-based file line; 1: keep). Output: mapped[m] gets move m's mapped points and their
/// thicknesses (appended); L's highest point and steepest slope (which set how travels clear
/// it). points counts the mapped points on; past params.most_points, an error naming the line.
std::optional<Error> map_gcode_layer(std::span<const GcodeLine> lines,
                                     const std::vector<GcodeMove>& moves,
                                     program::MovePaths& mapped, const LayerField& field,
                                     const MapBackParams& params,
                                     const std::vector<char>& planar_lines, LayerToolpaths& L,
                                     std::size_t& points);

/// A layer of the print: lines [begin, end) of the program, its index among the layers.
struct GcodeLayerSpan {
  std::size_t begin = 0, end = 0, layer = 0;
};

/// The layers of a run of whole layers of the print (a piece GcodePieceReader read), each from
/// its ;LAYER_CHANGE to the next; begin and end index `lines`.
std::vector<GcodeLayerSpan> gcode_layer_spans(std::span<const GcodeLine> lines);

/// map_gcode_layers' count for a layer it did not finish.
inline constexpr std::size_t kFailed = static_cast<std::size_t>(-1);

/// Each layer mapped by map_gcode_layer, side by side, each counting its own points from 0
/// (into layers[span.layer]). Output: each span's point count, or kFailed where it passed
/// most_points alone or the run was cancelled (the caller maps that layer again in order, to
/// report the error at the line the whole file's count passes it).
std::vector<std::size_t> map_gcode_layers(std::span<const GcodeLine> lines,
                                          const std::vector<GcodeLayerSpan>& spans,
                                          const std::vector<GcodeMove>& moves,
                                          program::MovePaths& mapped, const LayerField& field,
                                          const MapBackParams& params,
                                          const std::vector<char>& planar_lines,
                                          std::vector<LayerToolpaths>& layers, const Context& ctx);

}  // namespace nonplanar
