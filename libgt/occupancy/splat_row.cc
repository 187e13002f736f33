#include "libgt/occupancy/splat_row.h"

#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <cstdint>

namespace gt::occupancy {
namespace {

// Slab test per ray: z-interval inside the box, clipped to [e_0, e_D]; then the bins k0..k1
// it overlaps (a ray that misses gets no bits: its k0 and k1 are only kept in range).
// The AVX2 version below computes the same values with the same operations in the same
// order (min/max as the selects written here), so both give identical bits.
void SplatRowScalar(const RowArgs& r) {
  const double* ix = r.rays->inv_x.data() + r.row;
  const double* iy = r.rays->inv_y.data() + r.row;
  const double* iz = r.rays->inv_z.data() + r.row;
  uint64_t* known = r.vol->known.data() + r.row;
  uint64_t* occ = r.vol->occ.data() + r.row;
  const uint64_t occ_mask = r.occupied ? ~uint64_t{0} : 0;
  const Eigen::Vector3d &a = *r.a, &b = *r.b;
  const double e0 = r.e0, eD = r.eD;
  for (int u = r.ua; u <= r.ub; ++u) {
    const double ax = a.x() * ix[u], bx = b.x() * ix[u], ay = a.y() * iy[u], by = b.y() * iy[u],
                 az = a.z() * iz[u], bz = b.z() * iz[u];
    const double nx = ax < bx ? ax : bx, fx = bx > ax ? bx : ax;
    const double ny = ay < by ? ay : by, fy = by > ay ? by : ay;
    const double nz = az < bz ? az : bz, fz = bz > az ? bz : az;
    double z0 = nx > ny ? nx : ny;
    z0 = z0 > nz ? z0 : nz;
    z0 = z0 > e0 ? z0 : e0;
    double z1 = fx < fy ? fx : fy;
    z1 = z1 < fz ? z1 : fz;
    z1 = z1 < eD ? z1 : eD;
    uint64_t range;
    if (r.k_first < 0) {
      const int k0 = r.bins->First(z0 < eD ? z0 : e0);
      const int k1 = r.bins->Last(z1 > e0 ? z1 : eD);
      range = (~uint64_t{0} >> (63 - k1)) & (~uint64_t{0} << k0);
    } else {  // First(z0) is k_first + (z0 >= edge), Last(z1) is k_first + (z1 > edge)
      const double edge = r.bins->e_[r.k_first + 1];
      range =
          (z0 < edge ? uint64_t{1} << r.k_first : 0) | (z1 > edge ? uint64_t{1} << r.k_last : 0);
    }
    const uint64_t m = z1 > z0 ? range : 0;
    known[u] |= m;
    occ[u] |= m & occ_mask;
  }
}

std::atomic<bool> g_vector_kernels{true};

bool HasAvx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes && g_vector_kernels.load(std::memory_order_relaxed);
}

// Table start of four z (clamped cell), as EdgeIndex::Start: c <= 0 -> 0, c >= cells -> cells.
__attribute__((target("avx2"))) inline __m128i TableStart4(const int* start, __m256d z, __m256d lo,
                                                           __m256d inv_h, __m256d cells) {
  const __m256d zero = _mm256_setzero_pd();
  __m256d c = _mm256_mul_pd(_mm256_sub_pd(z, lo), inv_h);
  c = _mm256_blendv_pd(c, zero, _mm256_cmp_pd(c, zero, _CMP_LE_OQ));
  c = _mm256_blendv_pd(c, cells, _mm256_cmp_pd(c, cells, _CMP_GE_OQ));
  // The masked gathers (all lanes) avoid g++ 12's maybe-uninitialized on the plain ones.
  return _mm_mask_i32gather_epi32(_mm_setzero_si128(), start, _mm256_cvttpd_epi32(c),
                                  _mm_set1_epi32(-1), 4);
}

__attribute__((target("avx2"))) inline __m256d Gather4(const double* base, __m128i index) {
  return _mm256_mask_i32gather_pd(_mm256_setzero_pd(), base, index,
                                  _mm256_castsi256_pd(_mm256_set1_epi64x(-1)), 8);
}

// Four 64-bit lane masks (all ones / zero) as 32-bit lanes.
__attribute__((target("avx2"))) inline __m128i Narrow4(__m256d m) {
  const __m256i idx = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
  return _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(m), idx));
}

// The same as SplatRowScalar, four rays at a time (_mm256_min_pd(x, y) is x < y ? x : y and
// _mm256_max_pd(x, y) is x > y ? x : y, as the selects there). Masked-out lanes load zeros:
// their inverse directions are 0, so z1 > z0 fails and they would get no bits anyway.
template <bool kGeneral>
__attribute__((target("avx2"))) void SplatRowAvx2(const RowArgs& r) {
  const double* ix = r.rays->inv_x.data() + r.row;
  const double* iy = r.rays->inv_y.data() + r.row;
  const double* iz = r.rays->inv_z.data() + r.row;
  uint64_t* known = r.vol->known.data() + r.row;
  uint64_t* occ = r.vol->occ.data() + r.row;
  const EdgeIndex& bins = *r.bins;
  const __m256d ax = _mm256_set1_pd(r.a->x()), bx = _mm256_set1_pd(r.b->x());
  const __m256d ay = _mm256_set1_pd(r.a->y()), by = _mm256_set1_pd(r.b->y());
  const __m256d az = _mm256_set1_pd(r.a->z()), bz = _mm256_set1_pd(r.b->z());
  const __m256d e0 = _mm256_set1_pd(r.e0), eD = _mm256_set1_pd(r.eD);
  const __m256d lo = _mm256_set1_pd(bins.lo_), inv_h = _mm256_set1_pd(bins.inv_h_);
  const __m256d cells = _mm256_set1_pd(bins.cells_);
  const __m256i ones = _mm256_set1_epi64x(-1), c63 = _mm256_set1_epi64x(63);
  const __m256i occ_mask = r.occupied ? ones : _mm256_setzero_si256();
  const __m256d edge = _mm256_set1_pd(kGeneral ? 0.0 : bins.e_[r.k_first + 1]);
  const __m256i bit_first = _mm256_set1_epi64x(kGeneral ? 0 : int64_t{1} << r.k_first);
  const __m256i bit_last = _mm256_set1_epi64x(kGeneral ? 0 : int64_t{1} << r.k_last);
  const int* start = bins.start_.data();
  const double* e = bins.e_;
  const __m256i lane = _mm256_setr_epi64x(0, 1, 2, 3);
  for (int u = r.ua; u <= r.ub; u += 4) {
    // Lanes past the row's end (the last group only) are neither read nor written.
    const __m256i live = _mm256_cmpgt_epi64(_mm256_set1_epi64x(r.ub - u + 1), lane);
    const __m256d vx = _mm256_maskload_pd(ix + u, live), vy = _mm256_maskload_pd(iy + u, live),
                  vz = _mm256_maskload_pd(iz + u, live);
    const __m256d tax = _mm256_mul_pd(ax, vx), tbx = _mm256_mul_pd(bx, vx);
    const __m256d tay = _mm256_mul_pd(ay, vy), tby = _mm256_mul_pd(by, vy);
    const __m256d taz = _mm256_mul_pd(az, vz), tbz = _mm256_mul_pd(bz, vz);
    const __m256d nx = _mm256_min_pd(tax, tbx), fx = _mm256_max_pd(tbx, tax);
    const __m256d ny = _mm256_min_pd(tay, tby), fy = _mm256_max_pd(tby, tay);
    const __m256d nz = _mm256_min_pd(taz, tbz), fz = _mm256_max_pd(tbz, taz);
    __m256d z0 = _mm256_max_pd(nx, ny);
    z0 = _mm256_max_pd(z0, nz);
    z0 = _mm256_max_pd(z0, e0);
    __m256d z1 = _mm256_min_pd(fx, fy);
    z1 = _mm256_min_pd(z1, fz);
    z1 = _mm256_min_pd(z1, eD);
    __m256i range;
    if (kGeneral) {
      // k0 = First(z0 < eD ? z0 : e0), k1 = Last(z1 > e0 ? z1 : eD).
      const __m256d q0 = _mm256_blendv_pd(e0, z0, _mm256_cmp_pd(z0, eD, _CMP_LT_OQ));
      const __m256d q1 = _mm256_blendv_pd(eD, z1, _mm256_cmp_pd(z1, e0, _CMP_GT_OQ));
      __m128i k0 = TableStart4(start, q0, lo, inv_h, cells),
              k1 = TableStart4(start, q1, lo, inv_h, cells);
      // k += e[k + 1] <= z (First) / < z (Last): masks are -1, so subtract them.
      k0 = _mm_sub_epi32(k0, Narrow4(_mm256_cmp_pd(Gather4(e + 1, k0), q0, _CMP_LE_OQ)));
      k1 = _mm_sub_epi32(k1, Narrow4(_mm256_cmp_pd(Gather4(e + 1, k1), q1, _CMP_LT_OQ)));
      // k -= e[k] > z (First) / >= z (Last).
      k0 = _mm_add_epi32(k0, Narrow4(_mm256_cmp_pd(Gather4(e, k0), q0, _CMP_GT_OQ)));
      k1 = _mm_add_epi32(k1, Narrow4(_mm256_cmp_pd(Gather4(e, k1), q1, _CMP_GE_OQ)));
      const __m256i k0l = _mm256_cvtepi32_epi64(k0), k1l = _mm256_cvtepi32_epi64(k1);
      range = _mm256_and_si256(_mm256_srlv_epi64(ones, _mm256_sub_epi64(c63, k1l)),
                               _mm256_sllv_epi64(ones, k0l));
    } else {
      range = _mm256_or_si256(
          _mm256_and_si256(bit_first, _mm256_castpd_si256(_mm256_cmp_pd(z0, edge, _CMP_LT_OQ))),
          _mm256_and_si256(bit_last, _mm256_castpd_si256(_mm256_cmp_pd(z1, edge, _CMP_GT_OQ))));
    }
    const __m256i m =
        _mm256_and_si256(range, _mm256_castpd_si256(_mm256_cmp_pd(z1, z0, _CMP_GT_OQ)));
    long long* pk = reinterpret_cast<long long*>(known + u);
    long long* po = reinterpret_cast<long long*>(occ + u);
    _mm256_maskstore_epi64(pk, live, _mm256_or_si256(_mm256_maskload_epi64(pk, live), m));
    _mm256_maskstore_epi64(
        po, live, _mm256_or_si256(_mm256_maskload_epi64(po, live), _mm256_and_si256(m, occ_mask)));
  }
}

}  // namespace

void SplatRow(const RowArgs& r) {
  if (HasAvx2() && r.bins->one_step()) {
    if (r.k_first < 0) {
      SplatRowAvx2<true>(r);
    } else {
      SplatRowAvx2<false>(r);
    }
  } else {
    SplatRowScalar(r);
  }
}

void SetVectorKernelsForTesting(bool enabled) { g_vector_kernels.store(enabled); }

}  // namespace gt::occupancy
