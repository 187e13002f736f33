#include "libgt/geometry/patches.h"

#include <cmath>
#include <sstream>

#include "libgt/core/error.h"

namespace gt {
namespace {

struct Grid {
  int cells_w = 0, cells_h = 0;
};

Grid CheckLabels(const DirectionLabels& l, int stride, const char* name) {
  const size_t n = static_cast<size_t>(l.width) * l.height;
  if (l.width <= 0 || l.height <= 0 || l.labels.size() != n || l.warped_xy.size() != 2 * n) {
    throw InputError(name, "label map sizes do not match width x height");
  }
  Grid g{l.width / stride, l.height / stride};
  if (g.cells_w == 0 || g.cells_h == 0) {
    std::ostringstream msg;
    msg << "image " << l.width << "x" << l.height << " is smaller than one " << stride << "x"
        << stride << " cell";
    throw InputError(name, msg.str());
  }
  return g;
}

// Per cell: the anchor's label and its target cell in the other grid.
void CellsOf(const DirectionLabels& l, const Grid& own, const Grid& other, const PatchOptions& o,
             std::vector<uint8_t>* labels, std::vector<int32_t>* targets,
             std::vector<size_t>* anchor_index) {
  const size_t n = static_cast<size_t>(own.cells_w) * own.cells_h;
  labels->resize(n);
  targets->resize(n);
  anchor_index->resize(n);
  for (int r = 0; r < own.cells_h; ++r) {
    for (int c = 0; c < own.cells_w; ++c) {
      const size_t i = static_cast<size_t>(r) * own.cells_w + c;
      const size_t p = static_cast<size_t>(AnchorPixel(r, o.stride, o.anchor)) * l.width +
                       AnchorPixel(c, o.stride, o.anchor);
      (*labels)[i] = l.labels[p];
      (*anchor_index)[i] = p;
      (*targets)[i] = TargetCell(l.warped_xy[2 * p], l.warped_xy[2 * p + 1], other.cells_w,
                                 other.cells_h, o.stride, o.anchor);
    }
  }
}

}  // namespace

const char* AnchorName(Anchor a) { return a == Anchor::kCenter ? "center" : "corner"; }

int32_t TargetCell(float x, float y, int cells_w, int cells_h, int stride, Anchor anchor) {
  if (!std::isfinite(x) || !std::isfinite(y)) return -1;
  const double s = stride;
  double c, r;
  if (anchor == Anchor::kCenter) {
    c = std::floor((static_cast<double>(x) + 0.5) / s);
    r = std::floor((static_cast<double>(y) + 0.5) / s);
  } else {
    c = std::floor(static_cast<double>(x) / s + 0.5);
    r = std::floor(static_cast<double>(y) / s + 0.5);
  }
  if (!(c >= 0 && c < cells_w && r >= 0 && r < cells_h)) return -1;
  return static_cast<int32_t>(r) * cells_w + static_cast<int32_t>(c);
}

Anchor ParseAnchor(const std::string& name, const std::string& field) {
  if (name == "center") return Anchor::kCenter;
  if (name == "corner") return Anchor::kCorner;
  throw InputError(field, "expected one of center, corner, got '" + name + "'");
}

bool PatchOptions::Check(std::string* error) const {
  if (stride >= 1) return true;
  if (error) *error = "stride must be >= 1, got " + std::to_string(stride);
  return false;
}

PatchMatches ComputePatchMatches(const DirectionLabels& l01, const DirectionLabels& l10,
                                 const PatchOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("patch options", error);
  const Grid g0 = CheckLabels(l01, options.stride, "labels 0->1");
  const Grid g1 = CheckLabels(l10, options.stride, "labels 1->0");
  PatchMatches out;
  out.cells_w0 = g0.cells_w;
  out.cells_h0 = g0.cells_h;
  out.cells_w1 = g1.cells_w;
  out.cells_h1 = g1.cells_h;
  std::vector<int32_t> t01, t10;
  std::vector<size_t> p0, p1;
  CellsOf(l01, g0, g1, options, &out.cells0, &t01, &p0);
  CellsOf(l10, g1, g0, options, &out.cells1, &t10, &p1);

  const auto push = [&out](int32_t i, int32_t j, MatchType type, const float* xy) {
    out.matches.push_back(i);
    out.matches.push_back(j);
    out.match_type.push_back(static_cast<uint8_t>(type));
    out.match_xy.push_back(xy[0]);
    out.match_xy.push_back(xy[1]);
  };
  const auto vis = static_cast<uint8_t>(PixelLabel::kVisible);
  const auto occ = static_cast<uint8_t>(PixelLabel::kOccluded);
  const int32_t n0 = static_cast<int32_t>(out.cells0.size());
  const int32_t n1 = static_cast<int32_t>(out.cells1.size());
  for (int32_t i = 0; i < n0; ++i) {  // vv
    const int32_t j = t01[i];
    if (out.cells0[i] != vis || j < 0) continue;
    if (options.mutual && (out.cells1[j] != vis || t10[j] != i)) continue;
    push(i, j, MatchType::kVisibleVisible, &l01.warped_xy[2 * p0[i]]);
  }
  for (int32_t i = 0; i < n0; ++i) {  // vo
    const int32_t j = t01[i];
    if (out.cells0[i] != occ || j < 0) continue;
    push(i, j, MatchType::kVisibleOccluded, &l01.warped_xy[2 * p0[i]]);
  }
  for (int32_t j = 0; j < n1; ++j) {  // ov
    const int32_t i = t10[j];
    if (out.cells1[j] != occ || i < 0) continue;
    push(i, j, MatchType::kOccludedVisible, &l10.warped_xy[2 * p1[j]]);
  }
  return out;
}

MatchTypeCounts CountMatchTypes(const PatchMatches& matches) {
  MatchTypeCounts c;
  for (uint8_t t : matches.match_type) {
    switch (static_cast<MatchType>(t)) {
      case MatchType::kVisibleVisible:
        ++c.vv;
        break;
      case MatchType::kVisibleOccluded:
        ++c.vo;
        break;
      case MatchType::kOccludedVisible:
        ++c.ov;
        break;
    }
  }
  return c;
}

}  // namespace gt
