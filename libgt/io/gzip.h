// gzip (RFC 1952) members of a shard: `<field>.gz` holds the gzip of `<field>`'s bytes
// (recipe sample.compression: deflate, the default; docs/RECIPES.md "Sample compression").
// Standard tools read them: Python's gzip module, `gunzip`, WebDataset's decoders (which
// strip a ".gz" suffix).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace gt::io {

// gzip of `data` by libdeflate at `level` (1..12): no file name, modification time 0, so
// the same bytes, level and libdeflate version give the same output (libdeflate is
// deterministic for a version; another version may change the gzip bytes, never the plain
// ones, which is what tests/golden records).
std::string GzipBytes(std::string_view data, int level);

// The bytes of a gzip stream (one member). Throws InputError(what, ...) when it is not
// gzip, is truncated or corrupt, has trailing data, or inflates to more than max_bytes.
// Inflates with libdeflate (whole buffer, sized by the trailer) and falls back to zlib's
// streaming inflate for the error message.
std::string GunzipBytes(std::string_view gz, const std::string& what,
                        size_t max_bytes = size_t{1} << 31);

// The same into `out`, which must hold exactly the plain size (`size` bytes, e.g. the
// trailer's GzipTrailerSize): throws InputError(what, ...) when the data is bad or does not
// inflate to exactly `size` bytes.
void GunzipInto(std::string_view gz, char* out, size_t size, const std::string& what);

// The first plain bytes of a gzip stream, at most `max_bytes` (fewer when the stream is
// shorter): only that much is inflated. Throws InputError(what, ...) when it is not gzip or
// the data is bad before that point.
std::string GunzipPrefix(std::string_view gz, size_t max_bytes, const std::string& what);

// The plain size a gzip member's trailer records (ISIZE, the size mod 2^32; 0 when shorter
// than 4 bytes). Only a hint: the data may lie.
uint32_t GzipTrailerSize(std::string_view gz);

// The trailer's size, for a caller that allocates the output before GunzipInto: throws
// InputError(what, ...) when `gz` is not gzip or the size is one DEFLATE cannot reach from
// these bytes (over ~1032:1), so that a lying trailer never makes a large allocation.
size_t GzipPlainSize(std::string_view gz, const std::string& what);

}  // namespace gt::io
