// Base64 (RFC 4648, with '=' padding) of bytes: the one encoder, for the plan's arrays of
// doubles and the preview's buffers.
#pragma once

#include <string>
#include <string_view>

namespace nonplanar::core {

/// The bytes as base64: 4 characters per 3 bytes, the last group padded with '='.
std::string base64_encode(std::string_view bytes);

/// The alphabet, 64 characters: A–Z, a–z, 0–9, '+', '/'.
inline constexpr char kBase64Alphabet[] =
    "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

}  // namespace nonplanar::core
