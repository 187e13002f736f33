// Shard throughput: writing a shard of build-sized samples (TarShardWriter, including
// fsync, rename and the MD5 of the published file) and reading one back (libarchive
// member walk + MD5, what `occgt validate` and `occgt merge --verify` do per shard; the
// default merge reads no tar).
// Sample: two uint8 label maps 640x480 and two float32 depth maps 640x480 (~3.1 MB), 16
// samples per shard (~49 MB). Output folder: $OCCGT_BENCH_DIR or /tmp.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "libgt/io/md5.h"
#include "libgt/io/npy.h"
#include "libgt/shards/tar_shard.h"

namespace {

using gt::shards::Sample;

std::vector<Sample> MakeSamples(int n) {
  std::vector<uint8_t> labels(640 * 480);
  std::vector<float> depth(640 * 480);
  for (size_t i = 0; i < labels.size(); ++i) {
    labels[i] = static_cast<uint8_t>(i % 6);
    depth[i] = 0.5f + static_cast<float>(i % 977) * 0.01f;
  }
  std::vector<Sample> samples;
  for (int k = 0; k < n; ++k) {
    Sample s;
    s.key = "scene0707_00/" + std::to_string(100000 + k) + "_" + std::to_string(200000 + k);
    s.fields.push_back({"json", "{\"k\": " + std::to_string(k) + "}"});
    s.fields.push_back({"label01.npy", gt::io::EncodeNpy<uint8_t>({480, 640}, labels)});
    s.fields.push_back({"label10.npy", gt::io::EncodeNpy<uint8_t>({480, 640}, labels)});
    s.fields.push_back({"depth0.npy", gt::io::EncodeNpy<float>({480, 640}, depth)});
    s.fields.push_back({"depth1.npy", gt::io::EncodeNpy<float>({480, 640}, depth)});
    samples.push_back(std::move(s));
  }
  return samples;
}

std::string BenchDir() {
  const char* env = std::getenv("OCCGT_BENCH_DIR");
  const std::string dir =
      std::string(env != nullptr && *env ? env : "/tmp") + "/occgt_bench_shards";
  std::filesystem::create_directories(dir);
  return dir;
}

void BM_WriteShard(benchmark::State& state) {
  const auto samples = MakeSamples(16);
  const std::string path = BenchDir() + "/bench-000000.tar";
  int64_t bytes = 0;
  for (auto _ : state) {
    gt::shards::TarShardWriter writer(path);
    for (const auto& s : samples) writer.Add(s);
    bytes = writer.Finish().filesize;
  }
  state.SetBytesProcessed(state.iterations() * bytes);
  state.counters["shard_MB"] = static_cast<double>(bytes) / 1e6;
}
BENCHMARK(BM_WriteShard)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadShardAndMd5(benchmark::State& state) {
  const auto samples = MakeSamples(16);
  const std::string path = BenchDir() + "/bench-000001.tar";
  {
    gt::shards::TarShardWriter writer(path);
    for (const auto& s : samples) writer.Add(s);
    writer.Finish();
  }
  const auto bytes = static_cast<int64_t>(std::filesystem::file_size(path));
  for (auto _ : state) {
    int64_t members = 0;
    gt::shards::ForEachTarMember(
        path, [&](const gt::shards::TarMemberInfo&, std::string_view) { ++members; });
    benchmark::DoNotOptimize(members);
    benchmark::DoNotOptimize(gt::io::Md5HexOfFile(path));
  }
  state.SetBytesProcessed(state.iterations() * bytes);
}
BENCHMARK(BM_ReadShardAndMd5)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
