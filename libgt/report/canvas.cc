#include "libgt/report/canvas.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace gt::report {
namespace {
const cv::Scalar kWhite(255, 255, 255);
}  // namespace

void PutText(cv::Mat& image, const std::string& text, int x, int y, double scale) {
  cv::putText(image, text, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
}

cv::Mat SideBySide(const cv::Mat& a, const cv::Mat& b, int gap) {
  const int h = std::max(a.rows, b.rows);
  cv::Mat out(h, a.cols + gap + b.cols, CV_8UC3, kWhite);
  a.copyTo(out(cv::Rect(0, 0, a.cols, a.rows)));
  b.copyTo(out(cv::Rect(a.cols + gap, 0, b.cols, b.rows)));
  return out;
}

cv::Mat StackVertical(const std::vector<cv::Mat>& images) {
  int w = 0, h = 0;
  for (const cv::Mat& m : images) {
    w = std::max(w, m.cols);
    h += m.rows;
  }
  cv::Mat out(h, w, CV_8UC3, kWhite);
  int y = 0;
  for (const cv::Mat& m : images) {
    m.copyTo(out(cv::Rect(0, y, m.cols, m.rows)));
    y += m.rows;
  }
  return out;
}

namespace {
int Scaled(int px, double text_scale) { return static_cast<int>(std::lround(px * text_scale)); }
}  // namespace

double FittingFontScale(const std::string& text, double font, int max_width) {
  auto width = [&](double f) {
    int baseline = 0;
    return cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, f, 1, &baseline).width;
  };
  if (max_width < 1 || text.empty()) return font;
  // The width grows about linearly with the scale: one proportional step, then small ones
  // (glyph widths are rounded) until it fits.
  if (const int w = width(font); w > max_width) font *= static_cast<double>(max_width) / w;
  while (font > 0.05 && width(font) > max_width) font *= 0.97;
  return font;
}

cv::Mat TitleAbove(const cv::Mat& image, const std::string& title, double text_scale) {
  cv::Mat strip(Scaled(22, text_scale), image.cols, CV_8UC3, kWhite);
  const int pad = Scaled(4, text_scale);
  PutText(strip, title, pad, Scaled(16, text_scale),
          FittingFontScale(title, 0.45 * text_scale, image.cols - 2 * pad));
  return StackVertical({strip, image});
}

cv::Mat LegendStrip(const std::vector<LegendEntry>& entries, int width, int per_row,
                    const std::string& note, double text_scale) {
  const double font = 0.45 * text_scale;
  const int row_h = Scaled(22, text_scale), box = Scaled(14, text_scale);
  // Fewer entries a row when the widest text would not fit its cell.
  int widest = 0;
  for (const auto& e : entries) {
    int baseline = 0;
    widest = std::max(widest,
                      cv::getTextSize(e.text, cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline).width);
  }
  per_row = std::max(1, std::min(per_row, width / (widest + Scaled(34, text_scale))));
  const int rows =
      static_cast<int>((entries.size() + per_row - 1) / per_row) + (note.empty() ? 0 : 1);
  cv::Mat strip(rows * row_h + Scaled(6, text_scale), width, CV_8UC3, kWhite);
  const int cell_w = std::max(1, width / per_row);
  const int pad = Scaled(4, text_scale);
  // One entry a row and still too wide (a narrow picture): a smaller font for all entries.
  const int text_x = pad + box + Scaled(6, text_scale);
  double entry_font = font;
  for (const auto& e : entries) {
    entry_font = std::min(entry_font, FittingFontScale(e.text, font, cell_w - text_x - pad));
  }
  for (size_t e = 0; e < entries.size(); ++e) {
    const int x = static_cast<int>(e % per_row) * cell_w + pad;
    const int y = static_cast<int>(e / per_row) * row_h + pad;
    const cv::Rect swatch(x, y + Scaled(2, text_scale), box, box);
    cv::rectangle(strip, swatch, entries[e].color.Scalar(), cv::FILLED);
    cv::rectangle(strip, swatch, cv::Scalar(0, 0, 0), 1);
    PutText(strip, entries[e].text, x + box + Scaled(6, text_scale), y + box, entry_font);
  }
  if (!note.empty()) {
    PutText(strip, note, pad, (rows - 1) * row_h + Scaled(18, text_scale),
            FittingFontScale(note, font, width - 2 * pad));
  }
  return strip;
}

}  // namespace gt::report
