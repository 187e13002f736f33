#include "libgt/shards/sample.h"

#include <set>

#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/io/codec.h"
#include "libgt/io/gzip.h"
#include "libgt/io/npy.h"

namespace gt::shards {

std::string EncodeSampleColor(const uint8_t* rgb, int width, int height, ColorMember format,
                              const std::string& what) {
  const cv::Mat image(height, width, CV_8UC3, const_cast<uint8_t*>(rgb));
  if (format == ColorMember::kJpg) {
    return io::EncodeJpegBytes(image, io::ChannelOrder::kRgb, 95, what);
  }
  return io::EncodePngBytes(image, io::ChannelOrder::kRgb, 1, what, io::PngFilter::kSub);
}
namespace {

bool IsSafeKeyChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
         c == '_';
}

}  // namespace

std::string CheckSampleKey(std::string_view key) {
  if (key.empty()) return "empty sample key";
  for (char c : key) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) return "sample key " + Quoted(key) + " contains a control character";
    if (u >= 0x80) return "sample key " + Quoted(key) + " is not ASCII";
    if (c == '\\') return "sample key " + Quoted(key) + " contains a backslash";
  }
  if (key.front() == '/') return "sample key " + Quoted(key) + " is an absolute path";
  size_t start = 0;
  while (true) {
    const size_t slash = key.find('/', start);
    const std::string_view part =
        key.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
    if (part.empty()) return "sample key " + Quoted(key) + " has an empty path component";
    if (part == "..") return "sample key " + Quoted(key) + " contains '..'";
    if (part == ".") return "sample key " + Quoted(key) + " contains a '.' component";
    if (slash == std::string_view::npos) {
      if (part.find('.') != std::string_view::npos) {
        return "sample key " + Quoted(key) + " has a dot in its basename";
      }
      if (part.substr(0, 2) == "__") {
        return "sample key " + Quoted(key) + " has a basename starting with \"__\"";
      }
      break;
    }
    start = slash + 1;
  }
  if (key.size() + 2 > kMaxMemberPathBytes) {
    return "sample key " + Quoted(key) + " is too long for " + std::to_string(kMaxMemberPathBytes) +
           "-byte member paths";
  }
  return "";
}

std::string CheckFieldName(std::string_view field) {
  if (field.empty()) return "empty field name";
  if (!(field.front() >= 'a' && field.front() <= 'z')) {
    return "field name " + Quoted(field) + " must start with a lower-case letter";
  }
  for (char c : field) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.')) {
      return "field name " + Quoted(field) + " may contain only [a-z0-9_.]";
    }
  }
  if (field.back() == '.' || field.find("..") != std::string_view::npos) {
    return "field name " + Quoted(field) + " has an empty extension";
  }
  return "";
}

std::string CheckMemberPath(std::string_view key, std::string_view field) {
  const size_t len = key.size() + 1 + field.size();
  if (len <= kMaxMemberPathBytes) return "";
  return "member " + Quoted(std::string(key) + "." + std::string(field)) + " is " +
         std::to_string(len) + " bytes, longer than " + std::to_string(kMaxMemberPathBytes);
}

std::string CheckSample(const Sample& sample) {
  if (std::string e = CheckSampleKey(sample.key); !e.empty()) return e;
  if (sample.fields.empty()) return "sample " + Quoted(sample.key) + " has no fields";
  std::set<std::string> seen;
  for (const auto& f : sample.fields) {
    if (std::string e = CheckFieldName(f.name); !e.empty()) {
      return "sample " + Quoted(sample.key) + ": " + e;
    }
    if (!seen.insert(f.name).second) {
      return "sample " + Quoted(sample.key) + ": duplicate field " + Quoted(f.name);
    }
    if (std::string e = CheckMemberPath(sample.key, f.name); !e.empty()) return e;
  }
  return "";
}

std::string SanitizeKeyComponent(std::string_view component) {
  std::string out;
  out.reserve(component.size());
  for (char c : component) out += IsSafeKeyChar(c) ? c : '_';
  if (out.empty() || out.substr(0, 2) == "__") out.insert(out.begin(), 'x');
  return out;
}

std::string SanitizeScenePath(std::string_view scene) {
  std::string out;
  size_t start = 0;
  while (start <= scene.size()) {
    size_t slash = scene.find('/', start);
    if (slash == std::string_view::npos) slash = scene.size();
    const std::string_view part = scene.substr(start, slash - start);
    if (!part.empty() && part != "." && part != "..") {
      if (!out.empty()) out += '/';
      out += SanitizeKeyComponent(part);
    }
    start = slash + 1;
  }
  return out;
}

std::string MakeSampleKey(std::string_view scene, std::string_view frame0_id,
                          std::string_view frame1_id) {
  std::string key = SanitizeScenePath(scene);
  if (!key.empty()) key += '/';
  std::string base = SanitizeKeyComponent(frame0_id) + "_" + SanitizeKeyComponent(frame1_id);
  if (base.rfind("__", 0) == 0) base.insert(base.begin(), 'x');  // e.g. ids "_" and "7"
  key += base;
  if (std::string e = CheckSampleKey(key); !e.empty()) {
    throw InputError("sample key " + key, e);
  }
  return key;
}

bool SplitMemberPath(std::string_view member_path, std::string* key, std::string* field) {
  const size_t slash = member_path.rfind('/');
  const size_t base = slash == std::string_view::npos ? 0 : slash + 1;
  const size_t dot = member_path.find('.', base);
  if (dot == std::string_view::npos) return false;
  *key = std::string(member_path.substr(0, dot));
  *field = std::string(member_path.substr(dot + 1));
  return true;
}

std::string_view PlainFieldName(std::string_view field) {
  if (field.size() > 3 && field.substr(field.size() - 3) == ".gz") field.remove_suffix(3);
  return field;
}

std::string DecodeMember(std::string* field, std::string_view bytes, const std::string& where) {
  const size_t plain = PlainFieldName(*field).size();
  if (plain == field->size()) return std::string(bytes);
  field->resize(plain);
  // A .npy is inflated only up to the size its header declares.
  if (field->size() > 4 && field->compare(field->size() - 4, 4, ".npy") == 0) {
    return io::GunzipNpy(bytes, where);
  }
  return io::GunzipBytes(bytes, where);
}

}  // namespace gt::shards
