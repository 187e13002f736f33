#include "libgt/io/iphone_depth.h"

#include <libdeflate.h>
#include <lz4.h>
#include <zlib.h>

#include <cmath>
#include <cstring>

#include "libgt/core/error.h"
#include "libgt/io/file_read.h"

namespace gt::io {
namespace {

constexpr size_t kPixels = size_t{kIphoneDepthWidth} * kIphoneDepthHeight;
constexpr size_t kU16Bytes = kPixels * 2;
constexpr size_t kF32Bytes = kPixels * 4;

std::string FrameWhere(const std::string& path, int64_t frame) {
  return path + " (depth frame " + std::to_string(frame) + ")";
}

float Metres(float v) { return (std::isfinite(v) && v > 0.0f && v < 1e9f) ? v : 0.0f; }

DepthImage FromFloat(const char* bytes) {
  DepthImage d(kIphoneDepthWidth, kIphoneDepthHeight);
  for (size_t i = 0; i < kPixels; ++i) {
    float v;
    std::memcpy(&v, bytes + 4 * i, 4);
    d.values_m[i] = Metres(v);
  }
  return d;
}

uint32_t ReadU32(std::string_view bytes, size_t at) {
  uint32_t v = 0;
  for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<uint8_t>(bytes[at + k]);
  return v;
}

void PutU32(std::string* out, uint32_t v) {
  for (int k = 0; k < 4; ++k) out->push_back(static_cast<char>((v >> (8 * k)) & 0xFF));
}

std::string RawDeflate(const void* data, size_t size) {
  libdeflate_compressor* c = libdeflate_alloc_compressor(6);
  std::string out(libdeflate_deflate_compress_bound(c, size), '\0');
  const size_t n = libdeflate_deflate_compress(c, data, size, out.data(), out.size());
  libdeflate_free_compressor(c);
  GT_ASSERT(n > 0);
  out.resize(n);
  return out;
}

}  // namespace

IphoneDepthBin ScanIphoneDepthBin(const std::string& path) {
  const uint64_t size = FileSizeBytes(path);
  if (size == 0) throw InputError(path, "empty depth.bin");
  IphoneDepthBin out;
  // Walk the record chain: 4 bytes read per record.
  uint64_t at = 0;
  std::vector<ByteRange> records;
  bool chain = true;
  while (at < size) {
    if (size - at < 4) {
      chain = false;
      break;
    }
    const uint32_t n = ReadU32(ReadFileRange(path, at, 4, "depth record header"), 0);
    if (n == 0 || n > size - at - 4 || n > kF32Bytes + 1024) {
      chain = false;
      break;
    }
    records.push_back({at + 4, n});
    at += 4 + uint64_t{n};
  }
  if (chain && !records.empty()) {
    out.format = DepthFormat::kIphoneBinRecord;
    out.records = std::move(records);
  }
  return out;
}

namespace {

DepthImage DecodeRecord(std::string_view payload, const std::string& where) {
  std::string u16(kU16Bytes, '\0');
  const int n = LZ4_decompress_safe(payload.data(), u16.data(), static_cast<int>(payload.size()),
                                    static_cast<int>(u16.size()));
  if (n == static_cast<int>(kU16Bytes)) {
    DepthImage d(kIphoneDepthWidth, kIphoneDepthHeight);
    for (size_t i = 0; i < kPixels; ++i) {
      const uint16_t v = static_cast<uint16_t>(static_cast<uint8_t>(u16[2 * i]) |
                                               (static_cast<uint8_t>(u16[2 * i + 1]) << 8));
      d.values_m[i] = v == 0 ? 0.0f : static_cast<float>(v * 0.001);
    }
    return d;
  }
  std::string f32(kF32Bytes, '\0');
  libdeflate_decompressor* dec = libdeflate_alloc_decompressor();
  size_t produced = 0;
  const libdeflate_result rc = libdeflate_deflate_decompress(dec, payload.data(), payload.size(),
                                                             f32.data(), f32.size(), &produced);
  libdeflate_free_decompressor(dec);
  if (rc != LIBDEFLATE_SUCCESS || produced != kF32Bytes) {
    throw InputError(where, "depth record of " + std::to_string(payload.size()) +
                                " bytes is neither an LZ4 block of 256x192 uint16 nor raw deflate "
                                "of 256x192 float32");
  }
  return FromFloat(f32.data());
}

DepthImage InflateFrame(std::string_view bytes, int64_t index, const std::string& where) {
  if (index < 0) throw InputError(where, "no frame index");
  // Inflate the stream up to the frame (the encoding has no index: cost grows with the frame).
  z_stream z{};
  if (inflateInit2(&z, -15) != Z_OK) throw InputError(where, "zlib: cannot initialise");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  z.avail_in = static_cast<uInt>(bytes.size());
  std::string frame(kF32Bytes, '\0');
  int rc = Z_OK;
  for (int64_t i = 0; i <= index; ++i) {
    z.next_out = reinterpret_cast<Bytef*>(frame.data());
    z.avail_out = static_cast<uInt>(kF32Bytes);
    while (z.avail_out > 0 && rc == Z_OK) rc = inflate(&z, Z_NO_FLUSH);
    if (z.avail_out > 0) {
      inflateEnd(&z);
      throw InputError(where, rc == Z_STREAM_END
                                  ? "depth.bin holds " + std::to_string(i) + " frames"
                                  : "raw-deflate stream is corrupt or cut");
    }
  }
  inflateEnd(&z);
  return FromFloat(frame.data());
}

}  // namespace

DepthImage DecodeIphoneDepth(std::string_view bytes, const DepthSource& source) {
  const std::string where = FrameWhere(source.path, source.frame_index);
  if (source.format == DepthFormat::kIphoneBinRecord) return DecodeRecord(bytes, where);
  GT_ASSERT(source.format == DepthFormat::kIphoneBinDeflate);
  return InflateFrame(bytes, source.frame_index, where);
}

DepthImage ReadIphoneDepth(const DepthSource& source) {
  if (source.format == DepthFormat::kIphoneBinRecord) {
    return DecodeIphoneDepth(
        ReadFileRange(source.path, source.range.offset, source.range.size, "depth record"), source);
  }
  return DecodeIphoneDepth(ReadFileBytes(source.path), source);
}

std::string EncodeIphoneDepthBinDeflate(const std::vector<DepthImage>& frames) {
  std::string raw;
  for (const DepthImage& d : frames) {
    GT_ASSERT(d.width == kIphoneDepthWidth && d.height == kIphoneDepthHeight);
    raw.append(reinterpret_cast<const char*>(d.values_m.data()), kF32Bytes);
  }
  return RawDeflate(raw.data(), raw.size());
}

std::string EncodeIphoneDepthBinRecords(const std::vector<DepthImage>& frames, bool lz4) {
  std::string out;
  for (const DepthImage& d : frames) {
    GT_ASSERT(d.width == kIphoneDepthWidth && d.height == kIphoneDepthHeight);
    std::string payload;
    if (lz4) {
      std::string u16(kU16Bytes, '\0');
      for (size_t i = 0; i < kPixels; ++i) {
        const double mm = std::round(d.values_m[i] * 1000.0);
        const uint16_t v = mm > 0 && mm < 65535 ? static_cast<uint16_t>(mm) : 0;
        u16[2 * i] = static_cast<char>(v & 0xFF);
        u16[2 * i + 1] = static_cast<char>(v >> 8);
      }
      payload.resize(static_cast<size_t>(LZ4_compressBound(static_cast<int>(kU16Bytes))));
      const int n = LZ4_compress_default(u16.data(), payload.data(), static_cast<int>(kU16Bytes),
                                         static_cast<int>(payload.size()));
      GT_ASSERT(n > 0);
      payload.resize(static_cast<size_t>(n));
    } else {
      payload = RawDeflate(d.values_m.data(), kF32Bytes);
    }
    PutU32(&out, static_cast<uint32_t>(payload.size()));
    out += payload;
  }
  return out;
}

}  // namespace gt::io
