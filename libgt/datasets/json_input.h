// JSON files that people write (a generic dataset's scene.json, ScanNet++'s lists): parsed
// strictly. nlohmann::json keeps the last of two equal keys in an object, so an edited
// manifest with "K" twice would silently use the second; here it is refused.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace gt::datasets {

// The document in `text`, read from `path` (for messages). Throws gt::InputError
// "<path>: not valid JSON: ..." for a syntax error or a number beyond double's range, and
// "<path>: <field>: duplicate key" (field as frames[3].K) for a key given twice in one object.
nlohmann::json ParseJsonInput(std::string_view text, const std::string& path);

}  // namespace gt::datasets
