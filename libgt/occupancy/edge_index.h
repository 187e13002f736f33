// Internal to libgt/occupancy: the bin lookup of the exact frustum binning (frustum.cc).
//
// For bin edges e_0 < ... < e_D and planar depths z in [e_0, e_D]: First(z0) is the first
// bin k with e_{k+1} > z0 and Last(z1) the last bin k with e_k < z1, i.e. bins k..k' are
// those overlapping the interval (z0, z1) by the rule e_k < z1 && e_{k+1} > z0. Found
// through a uniform table whose cells are at most half as wide as the narrowest bin (so a
// cell holds at most one edge), corrected by one comparison with the edge on either side;
// bins too narrow for the table's cap are corrected by loops. Exact for any spacing
// (tests/occupancy/bins_test.cc checks it against a search of the edges).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace gt::occupancy {

// The edges must outlive the index (it keeps a pointer to them).
class EdgeIndex {
 public:
  explicit EdgeIndex(const std::vector<double>& e) : e_(e.data()), lo_(e.front()) {
    const int D = static_cast<int>(e.size()) - 1;
    double narrowest = e.back() - e.front();
    for (int k = 0; k < D; ++k) narrowest = std::min(narrowest, e[k + 1] - e[k]);
    const double wanted = std::max(std::ceil(2.0 * (e.back() - e.front()) / narrowest), 16.0);
    // Bins narrower than (far - near) / 2^19 (only from extreme options, e.g. a log spacing
    // from 1e-6 m): the table is capped and First/Last correct by loops instead.
    one_step_ = wanted <= double{1 << 20};
    cells_ = static_cast<int>(std::min(wanted, double{1 << 20}));
    last_ = D - 1;
    inv_h_ = cells_ / (e.back() - e.front());
    start_.resize(cells_ + 1);
    int k = 0;
    for (int c = 0; c <= cells_; ++c) {
      const double z = lo_ + c / inv_h_;
      while (k < D - 1 && e_[k + 1] <= z) ++k;
      start_[c] = k;
    }
  }
  // First bin k with e_{k+1} > z, for e_0 <= z < e_D. At k = D - 1, e_{k+1} = e_D > z; at
  // k = 0, e_0 <= z: neither correction leaves [0, D - 1].
  int First(double z) const {
    int k = Start(z);
    if (!one_step_) {
      while (k < last_ && e_[k + 1] <= z) ++k;
      while (k > 0 && e_[k] > z) --k;
      return k;
    }
    k += e_[k + 1] <= z;
    k -= e_[k] > z;
    return k;
  }
  // Last bin k with e_k < z, for e_0 < z <= e_D.
  int Last(double z) const {
    int k = Start(z);
    if (!one_step_) {
      while (k < last_ && e_[k + 1] < z) ++k;
      while (k > 0 && e_[k] >= z) --k;
      return k;
    }
    k += e_[k + 1] < z;
    k -= e_[k] >= z;
    return k;
  }
  // True when one correction step suffices (the vector kernel needs it).
  bool one_step() const { return one_step_; }

  int Start(double z) const {
    const double c = (z - lo_) * inv_h_;
    return start_[c <= 0 ? 0 : (c >= cells_ ? cells_ : static_cast<int>(c))];
  }
  // Read by SplatRowAvx2.
  const double* e_;
  double lo_, inv_h_ = 0;
  int cells_ = 0;
  int last_ = 0;
  bool one_step_ = true;
  std::vector<int> start_;
};

}  // namespace gt::occupancy
