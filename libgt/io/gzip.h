// gzip (RFC 1952) members of a shard: `<field>.gz` holds the gzip of `<field>`'s bytes
// (recipe sample.compression: deflate, the default; docs/RECIPES.md "Sample compression").
// Standard tools read them: Python's gzip module, `gunzip`, WebDataset's decoders (which
// strip a ".gz" suffix).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace gt::io {

// gzip of `data` at zlib `level` (1..9): no file name, modification time 0, so the same
// bytes and level give the same output.
std::string GzipBytes(std::string_view data, int level);

// The bytes of a gzip stream (one member). Throws InputError(what, ...) when it is not
// gzip, is truncated or corrupt, has trailing data, or inflates to more than max_bytes.
std::string GunzipBytes(std::string_view gz, const std::string& what,
                        size_t max_bytes = size_t{1} << 31);

}  // namespace gt::io
