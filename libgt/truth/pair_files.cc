#include "libgt/truth/pair_files.h"

#include <algorithm>
#include <cstdint>
#include <filesystem>

#include "gt/core/version.h"
#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/npy.h"

namespace gt::truth {
namespace {

using ordered_json = nlohmann::ordered_json;

ordered_json PoseJson(const Rigid3d& pose) {
  ordered_json rows = ordered_json::array();
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

ordered_json KJson(const Camera& c) {
  return {{c.fx, 0.0, c.cx}, {0.0, c.fy, c.cy}, {0.0, 0.0, 1.0}};
}

ordered_json SourceJson(const char* tool, const PairSource& s) {
  ordered_json j;
  j["tool"] = tool;
  j["occgt_version"] = kVersion;
  j["format"] = DatasetFormatName(s.format);
  j["scene"] = s.scene;
  j["frame0"] = {{"id", s.id0}, {"number", s.number0}};
  j["frame1"] = {{"id", s.id1}, {"number", s.number1}};
  j["resolution"] = {s.resolution.width, s.resolution.height};
  if (!s.device.empty()) j["device"] = s.device;
  if (s.tum_max_dt_s >= 0) j["tum_max_dt_s"] = s.tum_max_dt_s;
  if (s.depth_source != render::DepthSourceMode::kSensor) {
    j["depth_source"] = render::DepthSourceModeName(s.depth_source);
  }
  return j;
}

ordered_json CountsJson(const occupancy::FrustumVolume& v) {
  const occupancy::VolumeCounts c = occupancy::CountBins(v);
  const double total = static_cast<double>(c.occupied + c.free + c.unknown);
  return {{"occupied", c.occupied},
          {"free", c.free},
          {"unknown", c.unknown},
          {"occupied_fraction", total > 0 ? c.occupied / total : 0.0},
          {"free_fraction", total > 0 ? c.free / total : 0.0},
          {"unknown_fraction", total > 0 ? c.unknown / total : 0.0}};
}

}  // namespace

DirectionMetrics MetricsFromJson(const nlohmann::json& j) {
  DirectionMetrics m;
  m.sampled = j.at("sampled").get<int64_t>();
  m.valid = j.at("valid").get<int64_t>();
  for (int k = 0; k < kNumPixelLabels; ++k) {
    m.counts[k] = j.at("counts").at(PixelLabelName(static_cast<PixelLabel>(k))).get<int64_t>();
  }
  FinishMetrics(&m);
  return m;
}

nlohmann::ordered_json DepthAgreementJson(const render::DepthAgreement& a) {
  const double n = static_cast<double>(std::max<int64_t>(1, a.Total()));
  return {{"pixels", a.Total()},
          {"sensor_only", a.sensor_only},
          {"mesh_only", a.mesh_only},
          {"agree", a.agree},
          {"disagree", a.disagree},
          {"neither", a.neither},
          {"shares",
           {{"sensor_only", a.sensor_only / n},
            {"mesh_only", a.mesh_only / n},
            {"agree", a.agree / n},
            {"disagree", a.disagree / n}}}};
}

nlohmann::json MatrixJson(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

nlohmann::ordered_json LabelOptionsJson(const LabelOptions& lo) {
  return {{"min_depth_m", lo.min_depth_m},
          {"max_depth_m", lo.max_depth_m},
          {"abs_tol_m", lo.abs_tol_m},
          {"rel_tol", lo.rel_tol},
          {"relative_to", RelativeToName(lo.relative_to)},
          {"bounds", BoundsName(lo.bounds)},
          {"target_lookup", TargetLookupName(lo.target_lookup)},
          {"missing_target", MissingTargetName(lo.missing_target)},
          {"cheirality", lo.cheirality},
          {"projection_eps_m", lo.projection_eps_m}};
}

nlohmann::ordered_json PatchOptionsJson(const PatchOptions& po) {
  return {{"stride", po.stride}, {"anchor", AnchorName(po.anchor)}, {"mutual", po.mutual}};
}

nlohmann::ordered_json OccupancyOptionsJson(const PairTruthOptions& o) {
  const occupancy::BinOptions& bo = o.bins;
  const occupancy::FusionOptions& fo = o.fusion;
  nlohmann::ordered_json j = {{"mode", occupancy::OccupancyModeName(o.mode)},
                              {"bins",
                               {{"num_bins", bo.num_bins},
                                {"near_m", bo.near_m},
                                {"far_m", bo.far_m},
                                {"spacing", occupancy::BinSpacingName(bo.spacing)},
                                {"traversal", occupancy::TraversalName(bo.traversal)}}},
                              {"fusion",
                               {{"scope", occupancy::FusionScopeName(fo)},
                                {"voxel_m", fo.voxel_m},
                                {"max_range_m", fo.max_range_m},
                                {"downsample", fo.downsample},
                                {"remove_outliers", fo.remove_outliers}}}};
  // The filter's parameters only when it is on (the samples of other options keep their bytes).
  if (fo.remove_outliers) {
    j["fusion"]["outlier_k"] = fo.outlier_k;
    j["fusion"]["outlier_stddev"] = fo.outlier_stddev;
  }
  return j;
}

nlohmann::ordered_json FusionStatsJson(const occupancy::FusionStats& s) {
  return {{"frames", s.frames},
          {"pixels", s.pixels},
          {"invalid_pixels", s.invalid_pixels},
          {"out_of_key_range", s.out_of_key_range},
          {"after_downsample", s.after_downsample},
          {"downsample_fallbacks", s.downsample_fallbacks},
          {"outliers_removed", s.outliers_removed},
          {"inserted_points", s.inserted_points}};
}

namespace {
// Removes the file that names a folder's pair before its arrays are written again (a
// missing one is fine; one that cannot be removed stops the write).
void RemoveIndexFile(const std::string& path) {
  std::error_code ec;
  std::filesystem::remove(path, ec);
  if (ec) throw InputError(path, "cannot remove the earlier pair's file: " + ec.message());
}
}  // namespace

void WritePairFolder(const std::string& dir, const PairSource& source, const WorkingFrame& frame0,
                     const WorkingFrame& frame1, const PairTruthOptions& options,
                     const PairTruth& truth, int score_stride) {
  const PairLabels& p = truth.labels;
  const PatchMatches& pm = p.patches;
  const int64_t w = source.resolution.width, h = source.resolution.height;
  const int64_t m = static_cast<int64_t>(pm.size());
  // meta.json says which pair the arrays are, and is written last: an earlier pair's goes
  // first, so that a run killed among the arrays leaves a folder that names no pair rather
  // than this pair's arrays under the other pair's meta.json.
  RemoveIndexFile(dir + "/meta.json");
  io::WriteNpy<uint8_t>(dir + "/label01.npy", {h, w}, p.l01.labels);
  io::WriteNpy<uint8_t>(dir + "/label10.npy", {h, w}, p.l10.labels);
  io::WriteNpy<int32_t>(dir + "/matches.npy", {m, 2}, pm.matches);
  io::WriteNpy<uint8_t>(dir + "/match_type.npy", {m}, pm.match_type);
  io::WriteNpy<float>(dir + "/match_xy.npy", {m, 2}, pm.match_xy);
  io::WriteNpy<uint8_t>(dir + "/cells0.npy", {pm.cells_h0, pm.cells_w0}, pm.cells0);
  io::WriteNpy<uint8_t>(dir + "/cells1.npy", {pm.cells_h1, pm.cells_w1}, pm.cells1);

  const DirectionMetrics m01 = score_stride == 1 ? p.m01 : MetricsFromLabels(p.l01, score_stride);
  const DirectionMetrics m10 = score_stride == 1 ? p.m10 : MetricsFromLabels(p.l10, score_stride);
  ordered_json j = SourceJson("occgt pair", source);
  j["K0"] = KJson(frame0.camera);
  j["K1"] = KJson(frame1.camera);
  j["world_from_cam0"] = PoseJson(frame0.world_from_cam);
  j["world_from_cam1"] = PoseJson(frame1.world_from_cam);
  j["T_0to1"] = PoseJson(p.cam1_from_cam0);  // cam1_from_cam0
  j["preset"] = source.preset;
  j["label_options"] = LabelOptionsJson(options.labels);
  j["patch_options"] = PatchOptionsJson(options.patches);
  j["label_codes"] = ordered_json::object();
  for (int k = 0; k < kNumPixelLabels; ++k) {
    j["label_codes"][PixelLabelName(static_cast<PixelLabel>(k))] = k;
  }
  j["metrics"] = {{"01", MetricsJson<ordered_json>(p.m01)},
                  {"10", MetricsJson<ordered_json>(p.m10)}};
  j["score_stride"] = score_stride;
  j["score_metrics"] = {{"01", MetricsJson<ordered_json>(m01)},
                        {"10", MetricsJson<ordered_json>(m10)}};
  const MatchTypeCounts c = CountMatchTypes(pm);
  j["matches"] = {{"total", m}, {"vv", c.vv}, {"vo", c.vo}, {"ov", c.ov}};
  io::WriteFileAtomic(dir + "/meta.json", j.dump(2) + "\n");
}

void WriteOccupancyFolder(const std::string& dir, const PairSource& source,
                          const PairTruthOptions& options, const occupancy::PairOccupancy& volumes,
                          const ScopeMap* scope, bool dense) {
  const occupancy::FrustumVolume& v0 = volumes.cam0;
  const int64_t gw = v0.width, gh = v0.height;
  RemoveIndexFile(dir + "/occupancy.json");  // written last, as meta.json (WritePairFolder)
  io::WriteNpy<uint64_t>(dir + "/occ0.npy", {gh, gw}, volumes.cam0.occ);
  io::WriteNpy<uint64_t>(dir + "/known0.npy", {gh, gw}, volumes.cam0.known);
  io::WriteNpy<uint64_t>(dir + "/occ1.npy", {gh, gw}, volumes.cam1.occ);
  io::WriteNpy<uint64_t>(dir + "/known1.npy", {gh, gw}, volumes.cam1.known);
  ordered_json files = {"occ0.npy", "known0.npy", "occ1.npy", "known1.npy"};
  if (dense) {
    const int64_t d = options.bins.num_bins;
    // The shard's member names (folders written before: occupancy0.npy, occupancy1.npy).
    io::WriteNpy<uint8_t>(dir + "/occ0_dense.npy", {d, gh, gw}, DenseVolume(volumes.cam0));
    io::WriteNpy<uint8_t>(dir + "/occ1_dense.npy", {d, gh, gw}, DenseVolume(volumes.cam1));
    files.push_back("occ0_dense.npy");
    files.push_back("occ1_dense.npy");
  } else {
    // A folder written before with the dense volumes: theirs are now stale (of other bins
    // or frames), and occupancy.json no longer lists them.
    for (const char* stale : {"/occ0_dense.npy", "/occ1_dense.npy"}) {
      std::error_code ec;
      std::filesystem::remove(dir + stale, ec);
    }
  }
  const occupancy::BinOptions& bo = options.bins;
  const occupancy::FusionOptions& fo = options.fusion;
  ordered_json j = SourceJson("occgt occupancy", source);
  j["grid"] = {gw, gh};
  j["mode"] = occupancy::OccupancyModeName(options.mode);
  j["encoding"] = {{"occ", "uint64 [H/2, W/2], bit k set: bin k occupied"},
                   {"known", "uint64 [H/2, W/2], bit k set: bin k occupied or free"},
                   {"dense", "uint8 [bins, H/2, W/2]: 0 free, 1 occupied, 255 unknown"}};
  j["bins"] = {{"num_bins", bo.num_bins},
               {"near_m", bo.near_m},
               {"far_m", bo.far_m},
               {"spacing", occupancy::BinSpacingName(bo.spacing)},
               {"traversal", occupancy::TraversalName(bo.traversal)},
               {"edges_m", v0.edges_m}};
  ordered_json fused = ordered_json::array(), skipped = ordered_json::array();
  if (scope) {
    for (const std::string& id : scope->fused_ids) fused.push_back(id);
    for (const ScopeMap::Skipped& s : scope->skipped) {
      skipped.push_back({{"frame", s.frame_id}, {"reason", s.reason}});
    }
  }
  j["fusion"] = {{"scope", occupancy::FusionScopeName(fo)},
                 {"voxel_m", fo.voxel_m},
                 {"max_range_m", fo.max_range_m},
                 {"downsample", fo.downsample},
                 {"remove_outliers", fo.remove_outliers},
                 {"outlier_k", fo.outlier_k},
                 {"outlier_stddev", fo.outlier_stddev},
                 {"min_depth_m", options.labels.min_depth_m},
                 {"max_depth_m", options.labels.max_depth_m},
                 {"fused_frames", fused},
                 {"skipped_frames", skipped}};
  ordered_json stats = nullptr;  // two_point: no fusion
  if (volumes.fusion_stats) {
    stats = FusionStatsJson(*volumes.fusion_stats);
    if (scope) stats["leaf_nodes"] = scope->map.NumLeafNodes();
  }
  j["fusion"]["stats"] = stats;
  j["counts0"] = CountsJson(volumes.cam0);
  j["counts1"] = CountsJson(volumes.cam1);
  j["files"] = files;
  io::WriteFileAtomic(dir + "/occupancy.json", j.dump(2) + "\n");
}

}  // namespace gt::truth
