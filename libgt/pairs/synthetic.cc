#include "libgt/pairs/synthetic.h"

#include "libgt/core/error.h"

namespace gt::pairs {

void EnsureSyntheticDataset(const std::string& root, const SyntheticDatasetOptions& options) {
  throw InputError("dataset.format", "synthetic generation is not available in this build yet");
}

}  // namespace gt::pairs
