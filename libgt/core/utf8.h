// UTF-8 text: occgt's JSON outputs hold names (scenes, frames, paths) as UTF-8, so a name
// from the file system is checked before it is written.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

namespace gt {

// The Unicode scalar values of UTF-8 text; false when it is not UTF-8 (overlong forms,
// surrogates and values above U+10FFFF are not).
bool Utf8CodePoints(std::string_view text, std::vector<uint32_t>* out);

// True when `text` is UTF-8 (Utf8CodePoints' rule).
bool IsUtf8(std::string_view text);

}  // namespace gt
