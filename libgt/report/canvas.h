// Small composition helpers shared by the renderers of libgt/report (internal): panels side
// by side and stacked on a white background, titles, legend strips. Images are BGR
// CV_8UC3; text is OpenCV's Hershey simplex font at 0.45 scale, black, anti-aliased.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libgt/report/pictures.h"

namespace gt::report {

struct LegendEntry {
  Rgb color;
  std::string text;
};

// Black text with its baseline at (x, y).
void PutText(cv::Mat& image, const std::string& text, int x, int y, double scale = 0.45);
// a | gap (white) | b, top-aligned, the shorter one padded white below.
cv::Mat SideBySide(const cv::Mat& a, const cv::Mat& b, int gap = kPanelGap);
// Images one above the other, left-aligned, narrower ones padded white on the right.
cv::Mat StackVertical(const std::vector<cv::Mat>& images);
// The Hershey simplex scale at most `font` at which `text` is at most max_width pixels wide
// (cv::getTextSize): titles and legends of narrow pictures shrink rather than being cut.
double FittingFontScale(const std::string& text, double font, int max_width);
// A 22-pixel white strip with `title` above the image. text_scale enlarges the text and
// the strip (pictures that are shown downscaled stay readable: 1 / the display scale); a
// title wider than the image is drawn smaller (FittingFontScale), never cut.
cv::Mat TitleAbove(const cv::Mat& image, const std::string& title, double text_scale = 1.0);
// A white strip `width` wide: colour swatches with their text, `per_row` entries a row,
// and an optional note on a last line; text_scale as above; fewer entries a row when the
// widest does not fit its cell, and a smaller font when even one a row does not.
cv::Mat LegendStrip(const std::vector<LegendEntry>& entries, int width, int per_row,
                    const std::string& note, double text_scale = 1.0);

}  // namespace gt::report
