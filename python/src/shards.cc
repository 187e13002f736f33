// Bindings of libgt/shards for occgt.torch.ShardDataset: shard_index(split_dir) reads the
// split's index.json (shards::ReadShardIndex, the checks `occgt eval` and validate make);
// shard_samples(path) lists where the members of every sample of a tar shard are
// (shards::ListShardSamples: one pass over the headers with libarchive, the data is not
// read), without the GIL. A bad index or a bad or truncated shard raises ValueError naming
// the file (and the field, member or header byte).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "libgt/shards/sample.h"
#include "libgt/shards/sample_check.h"
#include "libgt/shards/split.h"
#include "libgt/shards/tar_shard.h"
#include "libgt/shards/views_sample_check.h"

namespace occgt_py {

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

// A sample's json and its arrays as the C++ checks take them: views of the NumPy arrays
// (little-endian, C order; kept alive here). ValueError naming `where` for bad JSON or a
// value that is not an array.
struct StoredSample {
  StoredSample(const std::string& meta_text, const py::dict& given, const std::string& where)
      : meta(nlohmann::json::parse(meta_text, nullptr, false)) {
    if (meta.is_discarded()) throw py::value_error(where + ".json: not valid JSON");
    for (const auto& [name, value] : given) {
      py::array a = py::array::ensure(value, py::array::c_style);
      if (!a) {
        throw py::value_error(where + "." + py::str(name).cast<std::string>() +
                              ": expected a NumPy array");
      }
      if (a.dtype().attr("byteorder").cast<std::string>() == ">") {  // as stored: either
        a = py::array::ensure(a.attr("astype")(a.dtype().attr("newbyteorder")("<")),
                              py::array::c_style);
      }
      gt::shards::StoredArray view;
      view.descr = a.dtype().attr("str").cast<std::string>();  // "<f4", "|u1"
      view.shape.assign(a.shape(), a.shape() + a.ndim());
      view.data = a.data();
      arrays[py::str(name).cast<std::string>()] = std::move(view);
      kept.push_back(std::move(a));
    }
  }
  nlohmann::json meta;
  std::map<std::string, gt::shards::StoredArray> arrays;
  std::vector<py::array> kept;  // alive while the checks read them
};

}  // namespace

void BindShards(py::module_& m) {
  m.def(
      "encode_sample_color",
      [](const py::array& rgb_in, const std::string& format) {
        if (format != "png" && format != "jpg") {
          throw py::value_error("format: expected 'png' or 'jpg', got '" + format + "'");
        }
        if (rgb_in.dtype().kind() != 'u' || rgb_in.itemsize() != 1 || rgb_in.ndim() != 3 ||
            rgb_in.shape(2) != 3 || rgb_in.shape(0) < 1 || rgb_in.shape(1) < 1) {
          throw py::value_error("rgb: expected uint8 [H, W, 3] with H, W >= 1");
        }
        const auto rgb = py::array_t<uint8_t, py::array::c_style>::ensure(rgb_in);
        std::string bytes;
        {
          py::gil_scoped_release no_gil;
          bytes = gt::shards::EncodeSampleColor(
              rgb.data(), static_cast<int>(rgb.shape(1)), static_cast<int>(rgb.shape(0)),
              format == "jpg" ? gt::shards::ColorMember::kJpg : gt::shards::ColorMember::kPng,
              "rgb");
        }
        return py::bytes(bytes);
      },
      "rgb"_a, "format"_a,
      "A sample's colour member (image0.png / image0.jpg) as occgt build writes it: rgb "
      "uint8 [H, W, 3] encoded as PNG or JPEG with the writer's settings (bytes). "
      "ValueError for another array or format.");
  m.def(
      "shard_index",
      [](const std::string& split_dir) {
        const gt::shards::ShardIndex index = gt::shards::ReadShardIndex(split_dir);
        py::list shards(index.shards.size());
        for (size_t i = 0; i < index.shards.size(); ++i) {
          const gt::shards::IndexedShard& s = index.shards[i];
          shards[i] = py::make_tuple(s.url, s.nsamples, s.filesize);
        }
        return py::make_tuple(index.path, index.name, std::move(shards));
      },
      "split_dir"_a,
      "The split's index.json as (path, name, [(url, nsamples, filesize)]), in shard order; "
      "every url is a file name in split_dir. ValueError naming index.json and the field "
      "(shardlist[i].url, ...) for a missing or bad index.");
  m.def(
      "shard_samples",
      [](const std::string& path) {
        std::vector<gt::shards::ShardSampleRange> samples;
        {
          py::gil_scoped_release no_gil;
          samples = gt::shards::ListShardSamples(path);
        }
        py::list out(samples.size());
        for (size_t i = 0; i < samples.size(); ++i) {
          const gt::shards::ShardSampleRange& s = samples[i];
          py::dict members;
          for (const gt::shards::ShardMemberRange& member : s.members) {
            members[py::str(member.field)] = py::make_tuple(member.offset, member.size);
          }
          out[i] = py::make_tuple(s.key, s.start, s.length, std::move(members));
        }
        return out;
      },
      "path"_a,
      "The samples of the tar shard `path`, in file order, as (key, start, length, members): "
      "the sample's bytes are [start, start + length) of the file, members maps each field "
      "('json', 'label01.npy', 'label01.npy.gz', ...) to (offset from start, size). One pass "
      "over the tar headers (libarchive; the data is skipped). ValueError naming the file and "
      "the member or header for a bad or truncated tar, a sample whose members are not "
      "consecutive or a field that repeats.");
  m.def(
      "check_pair_sample",
      [](const std::string& meta_text, const py::dict& arrays, const std::string& where) {
        const StoredSample sample(meta_text, arrays, where);
        std::vector<std::string> problems;
        {
          py::gil_scoped_release no_gil;
          problems = gt::shards::CheckPairSampleValues(sample.meta, sample.arrays, {});
        }
        if (!problems.empty()) throw py::value_error(where + "." + problems.front());
      },
      "meta"_a, "arrays"_a, "where"_a,
      "None once a stored pair sample's json (`meta`, its text) and the arrays read from it "
      "(`arrays`: member field name -> array, e.g. 'label01.npy') agree "
      "(shards::CheckPairSampleValues: poses and K, label codes and counts against metrics, "
      "depth against NO_DEPTH, cells, matches by their rules, occupancy words); else "
      "ValueError '<where>.<field>: <problem>' naming the first problem. Arrays not given are "
      "not checked (ShardDataset).");
  m.def(
      "check_views_sample",
      [](const std::string& meta_text, const py::dict& arrays, const std::string& where) {
        const StoredSample sample(meta_text, arrays, where);
        std::vector<std::string> problems;
        std::vector<uint8_t> seen_by;
        {
          py::gil_scoped_release no_gil;
          problems = gt::shards::CheckViewsSampleValues(sample.meta, sample.arrays, {}, &seen_by);
        }
        if (!problems.empty()) throw py::value_error(where + "." + problems.front());
        if (seen_by.empty()) {
          throw py::value_error(where + ": visible_in.npy and valid.npy are needed for seen_by");
        }
        const auto& shape = sample.arrays.at("visible_in.npy").shape;
        py::array_t<uint8_t> out({shape[0], shape[1], shape[2]});
        std::copy(seen_by.begin(), seen_by.end(), out.mutable_data());
        return out;
      },
      "meta"_a, "arrays"_a, "where"_a,
      "seen_by uint8 [N, H, W] once a stored N-view sample's json (`meta`, its text) and the "
      "arrays read from it (`arrays`: member field name -> array, e.g. 'visible_in.npy'; "
      "visible_in and valid at least) agree (shards::CheckViewsSampleValues: cameras and "
      "poses against the json, depth and valid, the bits, metrics, queries and tracks); else "
      "ValueError '<where>.<field>: <problem>' naming the first problem. Arrays not given are "
      "not checked (TupleShardDataset).");
}

}  // namespace occgt_py
