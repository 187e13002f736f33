#include "libgt/io/codec.h"

// clang-format off
#include <cstdio>  // before jpeglib.h, which uses FILE
#include <jpeglib.h>
#include <jerror.h>  // after jpeglib.h: the JWRN_ message codes
// clang-format on
#include <png.h>

#include <csetjmp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <utility>
#include <vector>

#include "libgt/core/error.h"

namespace gt::io {
namespace {

constexpr int64_t kMaxSide = 65535;
constexpr int64_t kMaxPixels = int64_t{1} << 28;

bool HostIsLittleEndian() {
  const uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

void CheckSize(int64_t width, int64_t height, const std::string& what, const char* format) {
  if (width <= 0 || height <= 0 || width > kMaxSide || height > kMaxSide ||
      width * height > kMaxPixels) {
    throw InputError(what, std::string(format) + " declares an empty or implausible size " +
                               std::to_string(width) + "x" + std::to_string(height) +
                               " (at most 65535 a side and 2^28 pixels)");
  }
}

uint32_t BigEndian32At(std::string_view b, size_t i) {
  return (static_cast<uint32_t>(static_cast<unsigned char>(b[i])) << 24) |
         (static_cast<uint32_t>(static_cast<unsigned char>(b[i + 1])) << 16) |
         (static_cast<uint32_t>(static_cast<unsigned char>(b[i + 2])) << 8) |
         static_cast<uint32_t>(static_cast<unsigned char>(b[i + 3]));
}

// ---------------------------------------------------------------------------------------
// PNG. libpng reports errors by longjmp to a setjmp in the function that called it. The
// functions holding a setjmp below have only trivially destructible locals, so no C++
// destructor is skipped; buffers live in their callers.

struct PngState {
  const unsigned char* data = nullptr;  // input (decoding)
  size_t size = 0;
  size_t pos = 0;
  std::string* out = nullptr;  // output (encoding)
  char message[200] = {};
};

void PngReadBytes(png_structp png, png_bytep dst, size_t n) {
  auto* s = static_cast<PngState*>(png_get_io_ptr(png));
  if (n > s->size - s->pos) png_error(png, "file ends inside a chunk");
  std::memcpy(dst, s->data + s->pos, n);
  s->pos += n;
}

void PngWriteBytes(png_structp png, png_bytep src, size_t n) {
  auto* s = static_cast<PngState*>(png_get_io_ptr(png));
  s->out->append(reinterpret_cast<const char*>(src), n);
}

void PngFlush(png_structp) {}

[[noreturn]] void PngOnError(png_structp png, png_const_charp message) {
  auto* s = static_cast<PngState*>(png_get_error_ptr(png));
  std::snprintf(s->message, sizeof s->message, "%s", message);
  png_longjmp(png, 1);
}

void PngOnWarning(png_structp, png_const_charp) {}

struct PngLayout {
  png_uint_32 width = 0;
  png_uint_32 height = 0;
  int channels = 0;
  int bit_depth = 0;
};

// Reads the header and sets the transformations; false on error (message in *s).
bool PngReadHeader(png_structp png, png_infop info, bool bgr, PngLayout* layout) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_user_limits(png, kMaxSide, kMaxSide);
  png_read_info(png, info);
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, colour_type = 0;
  png_get_IHDR(png, info, &width, &height, &bit_depth, &colour_type, nullptr, nullptr, nullptr);
  if (static_cast<int64_t>(width) * height > kMaxPixels) png_error(png, "image is too large");
  if (colour_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colour_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (colour_type == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_strip_alpha(png);
  if (bgr && (colour_type & PNG_COLOR_MASK_COLOR) != 0) png_set_bgr(png);
  if (bit_depth == 16 && HostIsLittleEndian()) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  layout->width = png_get_image_width(png, info);
  layout->height = png_get_image_height(png, info);
  layout->channels = png_get_channels(png, info);
  layout->bit_depth = png_get_bit_depth(png, info);
  return true;
}

bool PngReadRows(png_structp png, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  return true;
}

cv::Mat DecodePng(std::string_view bytes, ChannelOrder order, const std::string& what) {
  PngState state;
  state.data = reinterpret_cast<const unsigned char*>(bytes.data());
  state.size = bytes.size();
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, PngOnError, PngOnWarning);
  if (png == nullptr) throw InputError(what, "cannot start the PNG decoder");
  png_infop info = png_create_info_struct(png);
  struct Guard {
    png_structp* png;
    png_infop* info;
    ~Guard() { png_destroy_read_struct(png, info, nullptr); }
  } guard{&png, &info};
  if (info == nullptr) throw InputError(what, "cannot start the PNG decoder");
  png_set_read_fn(png, &state, PngReadBytes);

  PngLayout layout;
  if (!PngReadHeader(png, info, order == ChannelOrder::kBgr, &layout)) {
    throw InputError(what, std::string("cannot decode PNG: ") + state.message);
  }
  if ((layout.bit_depth != 8 && layout.bit_depth != 16) ||
      (layout.channels != 1 && layout.channels != 3 && layout.channels != 4)) {
    throw InputError(what, "cannot decode PNG: unexpected layout after expansion (" +
                               std::to_string(layout.channels) + " channels of " +
                               std::to_string(layout.bit_depth) + " bits)");
  }
  const int depth = layout.bit_depth == 16 ? CV_16U : CV_8U;
  cv::Mat image(static_cast<int>(layout.height), static_cast<int>(layout.width),
                CV_MAKETYPE(depth, layout.channels));
  std::vector<png_bytep> rows(layout.height);
  for (png_uint_32 v = 0; v < layout.height; ++v)
    rows[v] = image.ptr<png_byte>(static_cast<int>(v));
  if (!PngReadRows(png, rows.data())) {
    throw InputError(what, std::string("cannot decode PNG: ") + state.message);
  }
  return image;
}

bool PngWrite(png_structp png, png_infop info, const PngLayout& layout, int level, PngFilter filter,
              bool bgr, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  const int colour_type = layout.channels == 1   ? PNG_COLOR_TYPE_GRAY
                          : layout.channels == 3 ? PNG_COLOR_TYPE_RGB
                                                 : PNG_COLOR_TYPE_RGB_ALPHA;
  png_set_IHDR(png, info, layout.width, layout.height, layout.bit_depth, colour_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, level);
  if (filter == PngFilter::kSub) png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_write_info(png, info);
  if (bgr && layout.channels != 1) png_set_bgr(png);
  if (layout.bit_depth == 16 && HostIsLittleEndian()) png_set_swap(png);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  return true;
}

// ---------------------------------------------------------------------------------------
// JPEG. libjpeg's error_exit is replaced by a longjmp, with the same rule as for PNG.

struct JpegErrors {
  jpeg_error_mgr mgr;
  jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
  char warning[JMSG_LENGTH_MAX];  // first refused warning, "" if none
};

[[noreturn]] void JpegOnError(j_common_ptr c) {
  auto* e = reinterpret_cast<JpegErrors*>(c->err);
  (*c->err->format_message)(c, e->message);
  std::longjmp(e->jump, 1);
}

void JpegOnMessage(j_common_ptr c, int level) {
  if (level >= 0) return;  // trace messages
  auto* e = reinterpret_cast<JpegErrors*>(c->err);
  ++c->err->num_warnings;
  if (c->err->msg_code == JWRN_EXTRANEOUS_DATA || e->warning[0] != '\0') return;
  (*c->err->format_message)(c, e->warning);
}

void JpegSilent(j_common_ptr) {}

// Zeroes a JpegDecodeState or JpegEncodeState (its struct, C data only) and installs the
// error handlers above in its cinfo.
template <typename State>
void JpegInitState(State* s) {
  std::memset(s, 0, sizeof *s);
  JpegErrors* e = &s->errors;
  s->cinfo.err = jpeg_std_error(&e->mgr);
  e->mgr.error_exit = JpegOnError;
  e->mgr.emit_message = JpegOnMessage;
  e->mgr.output_message = JpegSilent;
}

struct JpegDecodeState {
  jpeg_decompress_struct cinfo;
  JpegErrors errors;
};

// 0: started; 1: libjpeg error (message in errors); 2: CMYK; 3: implausible size.
int JpegStart(JpegDecodeState* s, const unsigned char* data, size_t size, bool bgr) {
  if (setjmp(s->errors.jump)) return 1;
  jpeg_create_decompress(&s->cinfo);
  jpeg_mem_src(&s->cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&s->cinfo, TRUE);
  if (s->cinfo.jpeg_color_space == JCS_CMYK || s->cinfo.jpeg_color_space == JCS_YCCK) return 2;
  const int64_t w = s->cinfo.image_width, h = s->cinfo.image_height;
  if (w <= 0 || h <= 0 || w > kMaxSide || h > kMaxSide || w * h > kMaxPixels) return 3;
  s->cinfo.out_color_space =
      s->cinfo.num_components == 1 ? JCS_GRAYSCALE : (bgr ? JCS_EXT_BGR : JCS_RGB);
  jpeg_start_decompress(&s->cinfo);
  return 0;
}

bool JpegReadRows(JpegDecodeState* s, unsigned char** rows) {
  if (setjmp(s->errors.jump)) return false;
  while (s->cinfo.output_scanline < s->cinfo.output_height) {
    jpeg_read_scanlines(&s->cinfo, rows + s->cinfo.output_scanline,
                        s->cinfo.output_height - s->cinfo.output_scanline);
  }
  jpeg_finish_decompress(&s->cinfo);
  return true;
}

// Destroys a decompressor (created or only zeroed) when the decode leaves its scope.
struct JpegDestroyOnExit {
  jpeg_decompress_struct* cinfo;
  ~JpegDestroyOnExit() { jpeg_destroy_decompress(cinfo); }
};

// JpegStart with its outcomes as InputErrors.
void StartJpegOrThrow(JpegDecodeState* s, std::string_view bytes, bool bgr,
                      const std::string& what) {
  const int started =
      JpegStart(s, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), bgr);
  if (started == 1) throw InputError(what, std::string("cannot decode JPEG: ") + s->errors.message);
  if (started == 2) {
    throw InputError(what, "CMYK JPEG is not supported (convert it to RGB first)");
  }
  if (started == 3) CheckSize(s->cinfo.image_width, s->cinfo.image_height, what, "JPEG header");
}

// JpegReadRows with its failure and a refused warning as InputErrors.
void ReadJpegRowsOrThrow(JpegDecodeState* s, unsigned char** rows, const std::string& what) {
  if (!JpegReadRows(s, rows)) {
    throw InputError(what, std::string("cannot decode JPEG: ") + s->errors.message);
  }
  if (s->errors.warning[0] != '\0') {
    throw InputError(what, std::string("corrupt JPEG data: ") + s->errors.warning);
  }
}

cv::Mat DecodeJpeg(std::string_view bytes, ChannelOrder order, const std::string& what) {
  JpegDecodeState s;
  JpegInitState(&s);
  const JpegDestroyOnExit guard{&s.cinfo};
  StartJpegOrThrow(&s, bytes, order == ChannelOrder::kBgr, what);
  const int channels = s.cinfo.output_components;
  if (channels != 1 && channels != 3) {
    throw InputError(what, "cannot decode JPEG: " + std::to_string(channels) + " components");
  }
  cv::Mat image(static_cast<int>(s.cinfo.output_height), static_cast<int>(s.cinfo.output_width),
                CV_MAKETYPE(CV_8U, channels));
  std::vector<unsigned char*> rows(s.cinfo.output_height);
  for (size_t v = 0; v < rows.size(); ++v) rows[v] = image.ptr<unsigned char>(static_cast<int>(v));
  ReadJpegRowsOrThrow(&s, rows.data(), what);
  return image;
}

struct JpegEncodeState {
  jpeg_compress_struct cinfo;
  JpegErrors errors;
  unsigned char* buffer;  // malloc'ed by jpeg_mem_dest
  unsigned long size;
};

bool JpegWrite(JpegEncodeState* s, int width, int height, int channels, bool bgr, int quality,
               unsigned char** rows) {
  if (setjmp(s->errors.jump)) return false;
  jpeg_create_compress(&s->cinfo);
  jpeg_mem_dest(&s->cinfo, &s->buffer, &s->size);
  s->cinfo.image_width = static_cast<JDIMENSION>(width);
  s->cinfo.image_height = static_cast<JDIMENSION>(height);
  s->cinfo.input_components = channels;
  s->cinfo.in_color_space = channels == 1 ? JCS_GRAYSCALE : (bgr ? JCS_EXT_BGR : JCS_RGB);
  jpeg_set_defaults(&s->cinfo);
  jpeg_set_quality(&s->cinfo, quality, TRUE);
  jpeg_start_compress(&s->cinfo, TRUE);
  while (s->cinfo.next_scanline < s->cinfo.image_height) {
    jpeg_write_scanlines(&s->cinfo, rows + s->cinfo.next_scanline,
                         s->cinfo.image_height - s->cinfo.next_scanline);
  }
  jpeg_finish_compress(&s->cinfo);
  return true;
}

// ---------------------------------------------------------------------------------------
// Netpbm.

class PnmParser {
 public:
  PnmParser(std::string_view bytes, const std::string& what) : b_(bytes), what_(what) {}

  // Width and height, the first two header tokens (for NetpbmSize).
  std::pair<int64_t, int64_t> Size() {
    pos_ = 2;
    const int64_t width = HeaderNumber("width");
    return {width, HeaderNumber("height")};
  }

  cv::Mat Parse(ChannelOrder order) {
    const char kind = b_[1];
    const bool plain = kind <= '3';
    const bool bitmap = kind == '1' || kind == '4';
    const int channels = (kind == '3' || kind == '6') ? 3 : 1;
    const auto [width, height] = Size();
    const int64_t maxval = bitmap ? 1 : HeaderNumber("maxval");
    if (maxval < 1 || maxval > 65535)
      Fail("maxval must be 1..65535, got " + std::to_string(maxval));
    CheckSize(width, height, what_, "Netpbm header");
    const bool wide = maxval > 255;
    const auto samples = static_cast<size_t>(width * height * channels);
    if (plain) {
      SkipSpace();
      if (b_.size() - pos_ < samples) Fail(Short(samples, "samples"));
    } else {
      // Exactly one whitespace byte ends the header of a binary Netpbm.
      if (pos_ >= b_.size() || !IsSpace(b_[pos_]))
        Fail("expected one whitespace byte after the header");
      ++pos_;
      const size_t need =
          bitmap ? static_cast<size_t>((width + 7) / 8 * height) : samples * (wide ? 2 : 1);
      if (b_.size() - pos_ < need) Fail(Short(need, "bytes of pixel data"));
    }
    cv::Mat image(static_cast<int>(height), static_cast<int>(width),
                  CV_MAKETYPE(wide ? CV_16U : CV_8U, channels));
    const bool swap_rb = channels == 3 && order == ChannelOrder::kBgr;
    for (int v = 0; v < image.rows; ++v) {
      for (int u = 0; u < image.cols; ++u) {
        for (int c = 0; c < channels; ++c) {
          uint32_t value = 0;
          if (bitmap) {
            const uint32_t bit = plain ? PlainBit()
                                       : (static_cast<unsigned char>(
                                              b_[pos_ + static_cast<size_t>(v) * ((width + 7) / 8) +
                                                 static_cast<size_t>(u / 8)]) >>
                                          (7 - u % 8)) &
                                             1u;
            value = bit != 0 ? 0 : 255;
          } else {
            value = plain ? PlainNumber() : BinarySample(wide);
            if (value > maxval) {
              Fail("sample " + std::to_string(value) + " exceeds maxval " + std::to_string(maxval));
            }
          }
          const int dst = swap_rb ? 2 - c : c;
          if (wide) {
            image.ptr<uint16_t>(v)[u * channels + dst] = static_cast<uint16_t>(value);
          } else {
            image.ptr<uint8_t>(v)[u * channels + dst] = static_cast<uint8_t>(value);
          }
        }
      }
    }
    return image;
  }

 private:
  static bool IsSpace(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
  }
  [[noreturn]] void Fail(const std::string& problem) const {
    throw InputError(what_, "Netpbm: " + problem);
  }
  std::string Short(size_t need, const char* unit) const {
    return "truncated (needs " + std::to_string(need) + " " + unit + ", " +
           std::to_string(b_.size() - pos_) + " bytes left)";
  }
  void SkipSpace() {
    while (pos_ < b_.size() && IsSpace(b_[pos_])) ++pos_;
  }
  int64_t HeaderNumber(const char* field) {
    while (pos_ < b_.size() && (IsSpace(b_[pos_]) || b_[pos_] == '#')) {
      if (b_[pos_] == '#') {
        while (pos_ < b_.size() && b_[pos_] != '\n' && b_[pos_] != '\r') ++pos_;
      } else {
        ++pos_;
      }
    }
    return Digits(field);
  }
  int64_t Digits(const char* field) {
    const size_t start = pos_;
    int64_t v = 0;
    while (pos_ < b_.size() && b_[pos_] >= '0' && b_[pos_] <= '9') {
      if (pos_ - start >= 9) Fail(std::string(field) + " has too many digits");
      v = v * 10 + (b_[pos_] - '0');
      ++pos_;
    }
    if (pos_ == start) Fail(std::string("expected a decimal ") + field);
    return v;
  }
  uint32_t PlainNumber() {
    SkipSpace();
    const int64_t v = Digits("sample");
    if (pos_ < b_.size() && !IsSpace(b_[pos_])) Fail("expected whitespace after a sample");
    return static_cast<uint32_t>(v);
  }
  uint32_t PlainBit() {
    SkipSpace();
    if (pos_ >= b_.size() || (b_[pos_] != '0' && b_[pos_] != '1')) {
      Fail("expected a 0 or 1 in the bitmap");
    }
    return static_cast<uint32_t>(b_[pos_++] - '0');
  }
  uint32_t BinarySample(bool wide) {
    const auto at = [&](size_t i) {
      return static_cast<uint32_t>(static_cast<unsigned char>(b_[i]));
    };
    uint32_t v = wide ? (at(pos_) << 8) | at(pos_ + 1) : at(pos_);
    pos_ += wide ? 2 : 1;
    return v;
  }

  std::string_view b_;
  const std::string& what_;
  size_t pos_ = 0;
};

}  // namespace

std::string PngDamage(std::string_view bytes) {
  static constexpr char kSignature[] = "\x89PNG\r\n\x1a\n";
  if (bytes.size() < 8 || bytes.compare(0, 8, std::string_view(kSignature, 8)) != 0) return "";
  size_t pos = 8;
  uint64_t width = 0, height = 0, bits_per_pixel = 0, idat_bytes = 0;
  while (true) {
    if (bytes.size() - pos < 12) {
      return "truncated PNG (file ends at byte " + std::to_string(bytes.size()) +
             " before the IEND chunk)";
    }
    const uint64_t length = BigEndian32At(bytes, pos);
    const std::string_view type = bytes.substr(pos + 4, 4);
    if (length > bytes.size() - pos - 12) {
      return "truncated PNG (chunk '" + std::string(type) + "' at byte " + std::to_string(pos) +
             " needs " + std::to_string(length) + " data bytes past the end of the file)";
    }
    if (type == "IHDR" && length >= 13) {
      width = BigEndian32At(bytes, pos + 8);
      height = BigEndian32At(bytes, pos + 12);
      const auto bit_depth = static_cast<unsigned char>(bytes[pos + 16]);
      const auto colour_type = static_cast<unsigned char>(bytes[pos + 17]);
      static const int kChannels[7] = {1, 0, 3, 1, 2, 0, 4};  // by PNG colour type
      bits_per_pixel = colour_type < 7 ? uint64_t{bit_depth} * kChannels[colour_type] : 0;
    } else if (type == "IDAT") {
      idat_bytes += length;
    }
    pos += 12 + length;
    if (type == "IEND") break;
  }
  // Deflate compresses at most ~1032:1, so less IDAT data than raw / 1032 cannot hold the
  // image (libpng would print "Not enough image data" after a full-size allocation).
  const uint64_t raw_bytes = height * ((width * bits_per_pixel + 7) / 8);
  if (raw_bytes / 1032 > idat_bytes + 64) {
    return "PNG image data too short (" + std::to_string(idat_bytes) + " compressed bytes for " +
           std::to_string(width) + "x" + std::to_string(height) + ")";
  }
  return "";
}

std::string JpegDamage(std::string_view bytes) {
  const auto at = [&](size_t i) { return static_cast<unsigned char>(bytes[i]); };
  if (bytes.size() < 2 || at(0) != 0xFF || at(1) != 0xD8) return "";
  const std::string truncated =
      "truncated JPEG (no end-of-image marker in " + std::to_string(bytes.size()) + " bytes)";
  size_t pos = 2;
  while (true) {
    // A marker: 0xFF (fill bytes allowed), then its code.
    if (pos >= bytes.size() || at(pos) != 0xFF) return truncated;
    while (pos < bytes.size() && at(pos) == 0xFF) ++pos;
    if (pos >= bytes.size()) return truncated;
    const unsigned char marker = at(pos++);
    if (marker == 0xD9) return "";                                       // EOI
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (bytes.size() - pos < 2) return truncated;
    const size_t length = (static_cast<size_t>(at(pos)) << 8) | at(pos + 1);
    if (length < 2 || length > bytes.size() - pos) return truncated;
    pos += length;
    if (marker != 0xDA) continue;
    // Entropy-coded data after SOS: runs to the next marker other than a stuffed 0xFF00
    // or a restart marker.
    while (true) {
      if (bytes.size() - pos < 2) return truncated;
      if (at(pos) == 0xFF) {
        const unsigned char next = at(pos + 1);
        if (next != 0x00 && next != 0xFF && !(next >= 0xD0 && next <= 0xD7)) break;
        pos += next == 0xFF ? 1 : 2;
      } else {
        ++pos;
      }
    }
  }
}

bool NetpbmSize(std::string_view head, int* width, int* height) {
  if (head.size() < 2 || head[0] != 'P' || head[1] < '1' || head[1] > '6') return false;
  try {
    const auto [w, h] = PnmParser(head, "").Size();
    if (w <= 0 || h <= 0) return false;
    *width = static_cast<int>(w);
    *height = static_cast<int>(h);
    return true;
  } catch (const InputError&) {
    return false;
  }
}

bool DecodeJpegRgbInto(std::string_view bytes, const std::string& what, std::vector<uint8_t>* rgb,
                       int* width, int* height) {
  if (bytes.size() < 3 || static_cast<unsigned char>(bytes[0]) != 0xFF ||
      static_cast<unsigned char>(bytes[1]) != 0xD8 ||
      static_cast<unsigned char>(bytes[2]) != 0xFF) {
    return false;
  }
  if (std::string e = JpegDamage(bytes); !e.empty()) throw InputError(what, e);
  JpegDecodeState s;
  JpegInitState(&s);
  const JpegDestroyOnExit guard{&s.cinfo};
  StartJpegOrThrow(&s, bytes, /*bgr=*/false, what);
  if (s.cinfo.output_components != 3) return false;
  const size_t w = s.cinfo.output_width, h = s.cinfo.output_height;
  rgb->resize(w * h * 3);
  std::vector<unsigned char*> rows(h);
  for (size_t v = 0; v < h; ++v) rows[v] = rgb->data() + v * w * 3;
  ReadJpegRowsOrThrow(&s, rows.data(), what);
  *width = static_cast<int>(w);
  *height = static_cast<int>(h);
  return true;
}

cv::Mat DecodeImageBytes(std::string_view bytes, ChannelOrder order, const std::string& what) {
  static const char kPngSig[] = "\x89PNG\r\n\x1a\n";
  if (std::string e = PngDamage(bytes); !e.empty()) throw InputError(what, e);
  if (std::string e = JpegDamage(bytes); !e.empty()) throw InputError(what, e);
  if (bytes.size() >= 8 && bytes.compare(0, 8, std::string_view(kPngSig, 8)) == 0) {
    return DecodePng(bytes, order, what);
  }
  if (bytes.size() >= 3 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
      static_cast<unsigned char>(bytes[1]) == 0xD8 &&
      static_cast<unsigned char>(bytes[2]) == 0xFF) {
    return DecodeJpeg(bytes, order, what);
  }
  if (bytes.size() >= 2 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '6') {
    return PnmParser(bytes, what).Parse(order);
  }
  throw InputError(what, "unsupported image format (expected PNG, JPEG or Netpbm)");
}

std::string EncodePngBytes(const cv::Mat& image, ChannelOrder order, int level,
                           const std::string& what, PngFilter filter) {
  const int channels = image.channels();
  if (image.empty() || (image.depth() != CV_8U && image.depth() != CV_16U) ||
      (channels != 1 && channels != 3 && channels != 4) || level < 0 || level > 9) {
    throw InputError(what,
                     "PNG encoder: expected a non-empty 8- or 16-bit image of 1, 3 or 4 "
                     "channels and a level 0..9");
  }
  std::string out;
  PngState state;
  state.out = &out;
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, PngOnError, PngOnWarning);
  if (png == nullptr) throw InputError(what, "cannot start the PNG encoder");
  png_infop info = png_create_info_struct(png);
  struct Guard {
    png_structp* png;
    png_infop* info;
    ~Guard() { png_destroy_write_struct(png, info); }
  } guard{&png, &info};
  if (info == nullptr) throw InputError(what, "cannot start the PNG encoder");
  png_set_write_fn(png, &state, PngWriteBytes, PngFlush);
  PngLayout layout;
  layout.width = static_cast<png_uint_32>(image.cols);
  layout.height = static_cast<png_uint_32>(image.rows);
  layout.channels = channels;
  layout.bit_depth = image.depth() == CV_16U ? 16 : 8;
  std::vector<png_bytep> rows(static_cast<size_t>(image.rows));
  for (int v = 0; v < image.rows; ++v) rows[v] = const_cast<png_bytep>(image.ptr<png_byte>(v));
  if (!PngWrite(png, info, layout, level, filter, order == ChannelOrder::kBgr, rows.data())) {
    throw InputError(what, std::string("cannot encode PNG: ") + state.message);
  }
  return out;
}

std::string EncodeJpegBytes(const cv::Mat& image, ChannelOrder order, int quality,
                            const std::string& what) {
  const int channels = image.channels();
  if (image.empty() || image.depth() != CV_8U || (channels != 1 && channels != 3) || quality < 1 ||
      quality > 100) {
    throw InputError(what,
                     "JPEG encoder: expected a non-empty 8-bit image of 1 or 3 channels "
                     "and a quality 1..100");
  }
  JpegEncodeState s;
  JpegInitState(&s);
  struct Guard {
    JpegEncodeState* s;
    ~Guard() {
      jpeg_destroy_compress(&s->cinfo);
      std::free(s->buffer);
    }
  } guard{&s};
  std::vector<unsigned char*> rows(static_cast<size_t>(image.rows));
  for (int v = 0; v < image.rows; ++v)
    rows[v] = const_cast<unsigned char*>(image.ptr<unsigned char>(v));
  if (!JpegWrite(&s, image.cols, image.rows, channels, order == ChannelOrder::kBgr, quality,
                 rows.data())) {
    throw InputError(what, std::string("cannot encode JPEG: ") + s.errors.message);
  }
  return std::string(reinterpret_cast<const char*>(s.buffer), s.size);
}

}  // namespace gt::io
