// ScanNet++ iPhone depth.bin (docs/DATASETS.md "ScanNet++"; the toolkit's
// iphone/prepare_iphone_data.py): ARKit depth maps, 256 x 192 (W x H) each, in one of two
// encodings whose choice is not documented per scene:
//  - the whole file one raw-deflate stream (zlib window bits -15) of float32 metres, N maps
//    one after another (DepthFormat::kIphoneBinDeflate; map i = frame i);
//  - records [uint32 little-endian size][payload], one per frame, each payload an LZ4 block
//    of uint16 millimetres or a raw-deflate stream of float32 metres
//    (DepthFormat::kIphoneBinRecord; the payload is a ByteRange of the file).
// The toolkit tries the whole-file stream first; occgt first walks the record chain (cheap: a
// few bytes per record) and takes the file as records when the chain covers the file
// exactly, as a whole-file stream otherwise.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/core/depth.h"
#include "libgt/core/frame.h"

namespace gt::io {

inline constexpr int kIphoneDepthWidth = 256;
inline constexpr int kIphoneDepthHeight = 192;

struct IphoneDepthBin {
  DepthFormat format = DepthFormat::kIphoneBinDeflate;
  std::vector<ByteRange> records;  // kIphoneBinRecord: each frame's payload
};
// Looks at `path` (InputError naming it when unreadable or empty).
IphoneDepthBin ScanIphoneDepthBin(const std::string& path);

// The depth of one frame: source.format kIphoneBinDeflate (source.frame_index) or
// kIphoneBinRecord (source.range). InputError naming the file and the frame when the
// stream ends early, a payload is neither valid LZ4 of 98304 bytes nor raw deflate of 196608,
// or the file is damaged.
DepthImage ReadIphoneDepth(const DepthSource& source);
// The same from bytes in memory: the record's payload (kIphoneBinRecord) or the whole file
// (kIphoneBinDeflate).
DepthImage DecodeIphoneDepth(std::string_view bytes, const DepthSource& source);

// Writers (the synthetic fixture, tests): depth in metres (0 = none) of every frame.
std::string EncodeIphoneDepthBinDeflate(const std::vector<DepthImage>& frames);
// Each frame as an LZ4 record of uint16 mm (lz4 = true) or a raw-deflate float32 record.
std::string EncodeIphoneDepthBinRecords(const std::vector<DepthImage>& frames, bool lz4);

}  // namespace gt::io
