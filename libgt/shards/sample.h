// WebDataset samples: a key plus named fields, each field one tar member
// "<key>.<field>" (SHARDS.md "WebDataset tar shards").
//
// Key rules (checked by CheckSampleKey, enforced by every writer): ASCII printable only,
// '/'-separated relative path (no leading '/', no empty, "." or ".." components), no dot
// in the key's basename (readers split the member name at the first dot of the basename),
// no "__" prefix on the basename (WebDataset readers skip such names). Every member path
// "<key>.<field>" must be at most 100 bytes, so that a plain ustar header holds it and no
// pax / GNU long-name record is ever needed (wids and DALI break on those).
// Field names are lower case ASCII [a-z0-9_.], start with a letter and contain at least
// the extension ("json", "label01.npy").
//
// Conventional keys are "<scene>/<frame0>_<frame1>" (MakeSampleKey), e.g.
// "scene0707_00/000015_000585".
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace gt::shards {

// The colour member of a sample (image<c>.png / image<c>.jpg), as every writer stores it:
// `rgb` uint8 [height, width, 3] to PNG (level 1, Sub filters: the trainers decode these
// every epoch) or JPEG (quality 95, 4:2:0). `what` names the image in errors.
enum class ColorMember { kPng, kJpg };
std::string EncodeSampleColor(const uint8_t* rgb, int width, int height, ColorMember format,
                              const std::string& what);

// Longest member path a ustar header holds without the prefix field trick or pax records.
inline constexpr size_t kMaxMemberPathBytes = 100;

struct SampleField {
  std::string name;   // field name without the leading dot: "json", "label01.npy"
  std::string bytes;  // member content (a .npy file, a JSON document, PNG bytes, ...)
};

struct Sample {
  std::string key;                  // "scene0707_00/000015_000585"
  std::vector<SampleField> fields;  // written in this order
};

// "" when `key` is a valid sample key, else a one-line reason ("contains '..'", ...).
std::string CheckSampleKey(std::string_view key);
// "" when `field` is a valid field name, else a reason.
std::string CheckFieldName(std::string_view field);
// "" when the member "<key>.<field>" fits kMaxMemberPathBytes, else the reason (`member
// "<key>.<field>" is N bytes, longer than 100`): writers check a key against the longest field
// their samples carry before computing any sample.
std::string CheckMemberPath(std::string_view key, std::string_view field);
// "" when the whole sample is writable: key, every field name, no duplicate fields, at
// least one field, and every member path "<key>.<field>" <= kMaxMemberPathBytes.
std::string CheckSample(const Sample& sample);

// Makes one path component safe: ASCII letters, digits, '-' and '_' are kept, every other
// byte (dots, spaces, non-ASCII, control characters) becomes '_'; an empty result or
// one starting with "__" gets a leading 'x'. Deterministic and idempotent.
std::string SanitizeKeyComponent(std::string_view component);
// Sanitises a '/'-separated scene name component by component (empty components, "."
// and ".." are dropped), e.g. "hospital/Easy/P036" stays, "seq.01" -> "seq_01".
std::string SanitizeScenePath(std::string_view scene);
// "<SanitizeScenePath(scene)>/<frame0_id>_<frame1_id>" with sanitised frame ids.
// Throws gt::InputError("sample key <key>", reason) when the result still fails
// CheckSampleKey (e.g. too long).
std::string MakeSampleKey(std::string_view scene, std::string_view frame0_id,
                          std::string_view frame1_id);

// Splits a member path the WebDataset way: key = path up to the first dot of the
// basename, field = the rest after that dot. Returns false when the basename has no dot.
bool SplitMemberPath(std::string_view member_path, std::string* key, std::string* field);

// A compressed member (recipe sample.compression, io/gzip.h): "<field>.gz" holds the gzip
// of "<field>". When `field` ends with ".gz", strips it and returns the gunzipped bytes;
// otherwise returns `bytes` unchanged. Throws InputError(where, ...) on bad gzip data.
std::string DecodeMember(std::string* field, std::string_view bytes, const std::string& where);

// The field a member holds once decoded: `field` without a ".gz" suffix (DecodeMember's
// rule), for readers that choose members by field before inflating them.
std::string_view PlainFieldName(std::string_view field);

}  // namespace gt::shards
