// Helpers shared by the mesh parsers: face index checks (reading a whole file, the tokenizer
// and strict number parsing come from core/). Parsers take the bytes in memory so
// they can be fuzzed directly.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "core/file_bytes.hpp"
#include "core/text_tokens.hpp"
#include "nonplanar/mesh.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar::io {

// Reading files, the tokenizer and number parsing live in core/ (every parser uses them).
using core::FileBytes;
using core::parse_double;
using core::parse_error_at;
using core::parse_int;
using core::read_file_bytes;
using core::Tokenizer;

/// Checks that a triangle index list references existing vertices; returns an error naming
/// the first bad face otherwise.
std::optional<Error> check_face_indices(const TriangleMesh& mesh);

}  // namespace nonplanar::io
