#include "libgt/report/canvas.h"

#include <algorithm>
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

cv::Mat TitleAbove(const cv::Mat& image, const std::string& title) {
  cv::Mat strip(22, image.cols, CV_8UC3, kWhite);
  PutText(strip, title, 4, 16);
  return StackVertical({strip, image});
}

cv::Mat LegendStrip(const std::vector<LegendEntry>& entries, int width, int per_row,
                    const std::string& note) {
  const int row_h = 22;
  // Fewer entries a row when the widest text would not fit its cell.
  int widest = 0;
  for (const auto& e : entries) {
    int baseline = 0;
    widest = std::max(widest,
                      cv::getTextSize(e.text, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline).width);
  }
  per_row = std::max(1, std::min(per_row, width / (widest + 34)));
  const int rows =
      static_cast<int>((entries.size() + per_row - 1) / per_row) + (note.empty() ? 0 : 1);
  cv::Mat strip(rows * row_h + 6, width, CV_8UC3, kWhite);
  const int cell_w = std::max(1, width / per_row);
  for (size_t e = 0; e < entries.size(); ++e) {
    const int x = static_cast<int>(e % per_row) * cell_w + 4;
    const int y = static_cast<int>(e / per_row) * row_h + 4;
    cv::rectangle(strip, cv::Rect(x, y + 2, 14, 14), entries[e].color.Scalar(), cv::FILLED);
    cv::rectangle(strip, cv::Rect(x, y + 2, 14, 14), cv::Scalar(0, 0, 0), 1);
    PutText(strip, entries[e].text, x + 20, y + 14);
  }
  if (!note.empty()) PutText(strip, note, 4, (rows - 1) * row_h + 18);
  return strip;
}

}  // namespace gt::report
