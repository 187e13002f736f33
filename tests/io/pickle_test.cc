// io/pickle.h: the bytes of small values written by hand from the opcodes of pickle
// protocol 2 (Lib/pickletools.py), and a value of every kind read back by Python's own
// pickle (Debian's /usr/bin/python3) as the literal it stands for.
#include "libgt/io/pickle.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "libgt/core/error.h"
#include "tests/support/test_support.h"

namespace gt::io {
namespace {

using namespace std::string_literals;

TEST(Pickle, BytesOfSmallValuesByHand) {
  EXPECT_EQ(PickleBytes(PyValue::None()), "\x80\x02N."s);
  EXPECT_EQ(PickleBytes(PyValue::Int(1)), "\x80\x02J\x01\x00\x00\x00."s);
  EXPECT_EQ(PickleBytes(PyValue::Int(-2)), "\x80\x02J\xfe\xff\xff\xff."s);
  // 2^32: LONG1 with 8 bytes of two's complement, little-endian.
  EXPECT_EQ(PickleBytes(PyValue::Int(int64_t{1} << 32)),
            "\x80\x02\x8a\x08\x00\x00\x00\x00\x01\x00\x00\x00."s);
  // 1.5 = 0x3FF8000000000000, big-endian.
  EXPECT_EQ(PickleBytes(PyValue::Float(1.5)), "\x80\x02G\x3f\xf8\x00\x00\x00\x00\x00\x00."s);
  EXPECT_EQ(PickleBytes(PyValue::Str("ab")),
            "\x80\x02X\x02\x00\x00\x00"
            "ab."s);
  EXPECT_EQ(PickleBytes(PyValue::Dict({{"a", PyValue::List({PyValue::Int(1), PyValue::None()})}})),
            "\x80\x02}(X\x01\x00\x00\x00"
            "a](J\x01\x00\x00\x00"
            "Neu."s);
  EXPECT_EQ(PickleBytes(PyValue::Tuple({PyValue::Bool(true), PyValue::Bool(false)})),
            "\x80\x02\x88\x89\x86."s);
  EXPECT_EQ(PickleBytes(PyValue::List({})), "\x80\x02]."s);
  EXPECT_EQ(PickleBytes(PyValue::Tuple({})), "\x80\x02)."s);
}

TEST(Pickle, PythonReadsEveryKind) {
  const std::string dir = test::ScratchDir("pickle");
  std::vector<PyValue> four;
  for (int i = 0; i < 4; ++i) four.push_back(PyValue::Int(i));
  const PyValue v = PyValue::Dict({
      {"none", PyValue::None()},
      {"ints", PyValue::List({PyValue::Int(0), PyValue::Int(-1), PyValue::Int(2147483647),
                              PyValue::Int(-2147483648LL), PyValue::Int(2147483648LL),
                              PyValue::Int(-(int64_t{1} << 40)), PyValue::Int(INT64_MIN)})},
      {"floats",
       PyValue::List({PyValue::Float(0.1), PyValue::Float(-2.5e-300), PyValue::Float(1e300)})},
      {"str", PyValue::Str("Undistorted_SfM/0015/images/\xc3\xa9t\xc3\xa9.jpg")},
      {"tuples", PyValue::List({PyValue::Tuple({PyValue::Int(7)}), PyValue::Tuple(four),
                                PyValue::Tuple({})})},
      {"nested", PyValue::Tuple({PyValue::Tuple({PyValue::Int(3), PyValue::Int(9)}),
                                 PyValue::Float(0.25), PyValue::List({})})},
      {"bools", PyValue::List({PyValue::Bool(true), PyValue::Bool(false)})},
      {"empty", PyValue::Dict({})},
  });
  std::ofstream(dir + "/v.pkl", std::ios::binary) << PickleBytes(v);
  const std::string expected =
      "{'none': None, 'ints': [0, -1, 2147483647, -2147483648, 2147483648, -(1 << 40), "
      "-(1 << 63)], 'floats': [0.1, -2.5e-300, 1e300], "
      "'str': 'Undistorted_SfM/0015/images/\\u00e9t\\u00e9.jpg', "
      "'tuples': [(7,), (0, 1, 2, 3), ()], 'nested': ((3, 9), 0.25, []), "
      "'bools': [True, False], 'empty': {}}";
  const std::string script =
      "import pickle, sys\n"
      "v = pickle.load(open(sys.argv[1], 'rb'))\n"
      "want = " +
      expected +
      "\n"
      "assert v == want and list(v) == list(want), v\n"
      "assert all(type(a) is type(b) for a, b in zip(v['ints'] + v['bools'], want['ints'] + "
      "want['bools']))\n"
      "print('ok')\n";
  std::ofstream(dir + "/check.py") << script;
  const auto r = test::RunShell("/usr/bin/python3 '" + dir + "/check.py' '" + dir + "/v.pkl'");
  EXPECT_EQ(r.exit_code, 0) << r.stdout_text << r.stderr_text;
  EXPECT_EQ(r.stdout_text, "ok\n");
}

// PyValue as JSON (tuples and lists alike, as json.dumps writes them).
nlohmann::json ToJson(const PyValue& v) {
  switch (v.kind) {
    case PyValue::Kind::kNone:
      return nullptr;
    case PyValue::Kind::kBool:
      return v.int_value != 0;
    case PyValue::Kind::kInt:
      return v.int_value;
    case PyValue::Kind::kFloat:
      return v.float_value;
    case PyValue::Kind::kStr:
      return v.str;
    case PyValue::Kind::kList:
    case PyValue::Kind::kTuple: {
      nlohmann::json a = nlohmann::json::array();
      for (const PyValue& x : v.items) a.push_back(ToJson(x));
      return a;
    }
    case PyValue::Kind::kDict: {
      nlohmann::json o = nlohmann::json::object();
      for (size_t i = 0; i < v.keys.size(); ++i) o[v.keys[i]] = ToJson(v.items[i]);
      return o;
    }
  }
  return nullptr;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// Pickles written by Python and NumPy (protocols 2, 4 and 5): plain values, memo reuse, NumPy
// arrays of every dtype read here (C and Fortran order, big-endian), object arrays of str and
// None, NumPy scalars, and a dict shaped like LoFTR's MegaDepth scene_info; each read equals
// the JSON Python wrote of the same value (arrays through tolist()).
TEST(Pickle, ReadsWhatPythonAndNumpyWrite) {
  const std::string dir = test::ScratchDir("pickle_read");
  const std::string script = R"PY(
import json, pickle, sys
import numpy as np
out = sys.argv[1]
shared = [1, 2]
values = {
    "plain": {"a": None, "b": [True, False, 0, -1, 255, 65535, 2**31, -2**40, 2**63 - 1],
              "c": (1.5, -0.0, 1e-300), "d": "t\u00e9st", "e": (), "f": ((1,), (1, 2, 3, 4)),
              "g": [shared, shared], "h": b"raw"},
    "arrays": {"f8": np.arange(6, dtype=np.float64).reshape(2, 3) / 3,
               "f4": np.array([0.5, -2.25], np.float32), "i8": np.array([-3, 2**40]),
               "i4": np.array([[1, -2], [3, -4]], np.int32), "u1": np.array([0, 255], np.uint8),
               "u2": np.array([65535], np.uint16), "i1": np.array([-128, 127], np.int8),
               "b": np.array([True, False]), "U": np.array(["ab", "\u00e9\u4e2d\U0001F600"]),
               "fortran": np.asfortranarray(np.arange(6, dtype=np.int64).reshape(2, 3)),
               "big": np.array([1.25, -3.5], dtype=">f8"),
               "obj": np.array(["x.jpg", None], dtype=object), "empty": np.zeros((0, 3))},
    "scalars": [np.float64(0.75), np.int64(-7), np.float32(0.5), np.bool_(True)],
    "scene_info": {
        "image_paths": np.array(["Undistorted_SfM/0015/images/a.jpg", None, "b.jpg"], dtype=object),
        "depth_paths": np.array(["d/a.h5", None, "d/b.h5"], dtype=object),
        "intrinsics": np.array([np.eye(3), None, np.eye(3) * 2], dtype=object),
        "poses": np.array([np.eye(4), None, np.eye(4)], dtype=object),
        "pair_infos": np.array([((0, 2), np.float64(0.31), np.array([[1, 2]])),
                                ((2, 0), 0.5, np.zeros((0, 2)))], dtype=object),
    },
}
def plain(v):
    if isinstance(v, np.ndarray):
        return plain(v.tolist())
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, dict):
        return {k: plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if isinstance(v, bytes):
        return v.decode()
    return v
expected = {}
for name, v in values.items():
    for proto in (2, 4, 5):
        with open(f"{out}/{name}_{proto}.pkl", "wb") as f:
            pickle.dump(v, f, protocol=proto)
    expected[name] = plain(v)
with open(f"{out}/expected.json", "w") as f:
    json.dump(expected, f)
class Evil:
    def __reduce__(self):
        return (print, ("hi",))
with open(f"{out}/evil.pkl", "wb") as f:
    pickle.dump({"x": Evil()}, f, protocol=2)
print("ok")
)PY";
  std::ofstream(dir + "/make.py") << script;
  const auto r = test::RunShell("/usr/bin/python3 '" + dir + "/make.py' '" + dir + "'");
  ASSERT_EQ(r.exit_code, 0) << r.stdout_text << r.stderr_text;
  const nlohmann::json expected = nlohmann::json::parse(ReadAll(dir + "/expected.json"));
  for (const char* name : {"plain", "arrays", "scalars", "scene_info"}) {
    for (int proto : {2, 4, 5}) {
      const std::string path = dir + "/" + name + "_" + std::to_string(proto) + ".pkl";
      const PyValue v = ReadPickle(ReadAll(path), path);
      EXPECT_EQ(ToJson(v), expected[name]) << path;
    }
  }
  // No global outside NumPy's array reconstruction is called, or even looked up.
  try {
    (void)ReadPickle(ReadAll(dir + "/evil.pkl"), "evil.pkl");
    ADD_FAILURE() << "evil.pkl was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(".print is not allowed"), std::string::npos) << e.what();
  }
  // Every truncation and every single-byte change of a real pickle: a value or one
  // InputError, never a crash (ASan runs this too).
  const std::string good = ReadAll(dir + "/scene_info_4.pkl");
  for (size_t n = 0; n < good.size(); ++n) {
    EXPECT_THROW((void)ReadPickle(good.substr(0, n), "cut"), InputError) << n;
  }
  for (size_t i = 0; i < good.size(); ++i) {
    std::string bad = good;
    bad[i] = static_cast<char>(bad[i] ^ 0x5a);
    try {
      (void)ReadPickle(bad, "flipped");
    } catch (const InputError&) {
    }
  }
  // Nesting beyond 200 containers is refused before any recursion could overflow.
  const std::string lists = "\x80\x02" + std::string(1000, ']') + std::string(999, 'a') + ".";
  const std::string tuples = "\x80\x02N" + std::string(1000, '\x85') + ".";
  for (const std::string& deep : {lists, tuples}) {
    try {
      (void)ReadPickle(deep, "deep");
      ADD_FAILURE() << "deep nesting was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("nested deeper than 200"), std::string::npos)
          << e.what();
    }
  }
  // Our own writer's output reads back as itself.
  const PyValue mine = PyValue::Dict(
      {{"k", PyValue::Tuple({PyValue::Int(-1 - (int64_t{1} << 40)), PyValue::Float(0.1)})}});
  EXPECT_EQ(ToJson(ReadPickle(PickleBytes(mine), "mine")), ToJson(mine));
}

}  // namespace
}  // namespace gt::io
