// io/pickle.h: the bytes of small values written by hand from the opcodes of pickle
// protocol 2 (Lib/pickletools.py), and a value of every kind read back by Python's own
// pickle (Debian's /usr/bin/python3) as the literal it stands for.
#include "libgt/io/pickle.h"

#include <gtest/gtest.h>

#include <fstream>

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

}  // namespace
}  // namespace gt::io
