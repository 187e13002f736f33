#include "libgt/core/utf8.h"

namespace gt {

bool Utf8CodePoints(std::string_view text, std::vector<uint32_t>* out) {
  out->clear();
  for (size_t i = 0; i < text.size();) {
    const auto b = static_cast<unsigned char>(text[i]);
    int extra = 0;
    uint32_t code = 0, min = 0;
    if (b < 0x80) {
      code = b;
    } else if ((b & 0xE0) == 0xC0) {
      extra = 1, code = b & 0x1F, min = 0x80;
    } else if ((b & 0xF0) == 0xE0) {
      extra = 2, code = b & 0x0F, min = 0x800;
    } else if ((b & 0xF8) == 0xF0) {
      extra = 3, code = b & 0x07, min = 0x10000;
    } else {
      return false;
    }
    if (i + extra >= text.size() && extra > 0) return false;  // cut short
    for (int k = 1; k <= extra; ++k) {
      const auto c = static_cast<unsigned char>(text[i + k]);
      if ((c & 0xC0) != 0x80) return false;
      code = (code << 6) | (c & 0x3F);
    }
    if (code < min || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return false;
    out->push_back(code);
    i += 1 + extra;
  }
  return true;
}

bool IsUtf8(std::string_view text) {
  std::vector<uint32_t> codes;
  return Utf8CodePoints(text, &codes);
}

}  // namespace gt
