// Image codecs: PNG through libpng, JPEG through libjpeg-turbo, Netpbm (P1..P6) parsed here.
//
// occgt does not link OpenCV's imgcodecs: that library pulls in GDAL and ~140 shared
// libraries whose symbol lookup cost ~0.1 s at every process start (docs/PERFORMANCE.md,
// "Threads and tasks"). Images are carried in cv::Mat (opencv_core) all the same.
//
// Decoded images are 8- or 16-bit (CV_8U / CV_16U, 16-bit samples in host byte order) with
// 1, 3 or 4 channels, colour channels in the requested order:
//  - PNG: grey, grey below 8 bits (expanded to 0..255), RGB, RGBA; a palette becomes RGB,
//    or RGBA when it has a tRNS chunk; grey+alpha becomes grey (the alpha is dropped); no
//    gamma or colour-profile conversion.
//  - JPEG: grey or colour (YCbCr/RGB), integer DCT, fancy upsampling (libjpeg's defaults);
//    no EXIF rotation; CMYK/YCCK JPEGs are refused. A JPEG with corrupt entropy-coded data
//    (libjpeg's "corrupt data" warnings) is refused rather than decoded with grey blocks;
//    only the harmless "extraneous bytes before marker" warning is allowed.
//  - Netpbm: PBM (0 = white, 1 = black, as 255 / 0), PGM, PPM, binary or plain; samples are
//    kept as stored (no rescaling by maxval); maxval above 255 gives 16 bits.
// Sizes are checked before any pixel buffer is allocated: at most 65535 pixels a side and
// 2^28 pixels in all, and a binary Netpbm must hold all its samples.
//
// Every failure is an InputError(what, problem); no library prints on stderr.
#pragma once

#include <opencv2/core/mat.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace gt::io {

enum class ChannelOrder { kRgb, kBgr };

// "" when `bytes` are not a PNG or a structurally complete one (signature, then chunks
// that fit in the file, ending with IEND); else the problem ("truncated PNG (...)").
// Checked before decoding so that a cut file is one clear InputError and libpng never
// prints its own "libpng error: Read Error" line on stderr.
std::string PngDamage(std::string_view bytes);
// "" when `bytes` are not a JPEG or one whose scan data reaches the EOI marker (segments
// walked by their lengths, entropy-coded data scanned for the next marker); else the
// problem ("truncated JPEG (...)"), named before libjpeg's own "premature end" message.
std::string JpegDamage(std::string_view bytes);

// Decodes PNG, JPEG or Netpbm bytes, told apart by their signature; anything else is an
// InputError ("unsupported image format ..."). PngDamage and JpegDamage are checked first.
cv::Mat DecodeImageBytes(std::string_view bytes, ChannelOrder order, const std::string& what);

// A 3-component JPEG decoded straight into `rgb` ([height, width, 3], R G B; no cv::Mat in
// between), with every check of DecodeImageBytes. Returns false, `rgb` untouched, when the
// bytes are not a JPEG or not of 3 components (the caller decodes them the general way).
bool DecodeJpegRgbInto(std::string_view bytes, const std::string& what, std::vector<uint8_t>* rgb,
                       int* width, int* height);

// Width and height from the first two tokens of a Netpbm header (P1..P6; comments and
// whitespace as DecodeImageBytes reads them), without reading further; false when `head`
// is not a Netpbm file or these tokens are missing or malformed. ReadImageSize uses it.
bool NetpbmSize(std::string_view head, int* width, int* height);

// PNG row filters: libpng's adaptive choice per row (the smallest files), or Sub on every
// row (faster to decode: ShardDataset with images 1.50x the samples/s, the PNGs 6 % larger
// on the synthetic demo; N-view shards of real TartanAir frames 1.19x, the PNGs 1 % smaller;
// docs/PERFORMANCE.md).
enum class PngFilter { kAdaptive, kSub };

// 8-bit (CV_8UC1 grey, CV_8UC3 colour in `order`, CV_8UC4 with alpha) or 16-bit grey or
// colour (CV_16UC1 / CV_16UC3) to PNG with zlib level `level` (0..9) and row filters
// `filter`.
std::string EncodePngBytes(const cv::Mat& image, ChannelOrder order, int level,
                           const std::string& what, PngFilter filter = PngFilter::kAdaptive);

// CV_8UC1 or CV_8UC3 (colour in `order`) to a baseline JPEG of `quality` (1..100), 4:2:0
// chroma for colour, standard Huffman tables (libjpeg's defaults).
std::string EncodeJpegBytes(const cv::Mat& image, ChannelOrder order, int quality,
                            const std::string& what);

}  // namespace gt::io
