// The OPC package (zip) around a 3MF model, repaired where lib3mf refuses it: PrusaSlicer's
// command line writes a relationship to /Metadata/thumbnail.png without the picture, and
// lib3mf then fails with "Could not create OPC Part".
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace nonplanar::io {

/// The package with every relationship whose target is not in it removed, rebuilt as a zip
/// of stored entries; nullopt when nothing was removed or the zip cannot be read (ZIP64,
/// encryption, an entry over 1 GB, a bad deflate stream). `dropped` gets the targets removed.
std::optional<std::string> drop_dangling_relationships(std::string_view zip,
                                                       std::vector<std::string>* dropped);

/// The uncompressed bytes of entry `name` (leading '/' ignored); nullopt when the zip cannot
/// be read (as above), has no such entry, or it is larger than `max_size` bytes. Only that
/// entry is inflated.
std::optional<std::string> zip_entry(std::string_view zip, std::string_view name,
                                     std::size_t max_size = std::size_t(1) << 30);

}  // namespace nonplanar::io
