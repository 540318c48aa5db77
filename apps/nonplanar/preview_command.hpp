// The preview page as `preview` and `slice --preview` write it.
#pragma once

#include <string>
#include <string_view>

#include "nonplanar/config.hpp"
#include "nonplanar/preview.hpp"

namespace nonplanar::cli {

/// GCODE's page beside it: the same name with ".html".
std::string preview_path_for(const std::string& gcode);

/// What a page shows: the G-code (its text and file name), the mesh (null: none) and marks.
struct PreviewInput {
  std::string name;        ///< the G-code's file, for the title and errors
  std::string_view gcode;  ///< its text
  std::string html;        ///< the page to write (atomically)
  const TriangleMesh* mesh = nullptr;
  PreviewMarks marks;
};

/// Reads the G-code (tolerantly), estimates its time with cfg's machine limits and writes
/// the page. Returns the buffers shown (for their counts). Errors: invalid_argument (no move
/// to show), io_error (the page could not be written).
Expected<PreviewBuffers> write_preview(const PreviewInput& in, const PrintConfig& cfg,
                                       PreviewSummary summary);

}  // namespace nonplanar::cli
