// Recipe YAML -> gt::pipeline::ParseRecipe: YAML parsing, YAML-to-JSON typing, schema
// validation (valijson), mapping onto the Options structs and Recipe::Check; a recipe that
// loads must also normalise (ToJson) and digest.
#include <cstdint>

#include "libgt/pipeline/recipe.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string name = "fuzz-recipe.yaml";
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    const gt::pipeline::Recipe r = gt::pipeline::ParseRecipe(std::string(gt::fuzz::Bytes(data, size)),
                                                       name, "/nonexistent-occgt-fuzz");
    std::string error;
    if (!r.Check(&error)) std::abort();
    (void)r.ToJson().dump();
    (void)r.Digest();
  });
  return 0;
}
