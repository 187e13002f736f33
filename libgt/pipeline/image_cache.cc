#include "libgt/pipeline/image_cache.h"

#include <stdexcept>

namespace gt::pipeline {

ImageCache::ImageCache(size_t max_images, Encoder encode)
    : max_images_(max_images), encode_(std::move(encode)) {
  if (max_images_ < 1) throw std::invalid_argument("ImageCache: max_images must be >= 1");
  if (!encode_) throw std::invalid_argument("ImageCache: no encoder");
}

std::shared_ptr<ImageCache::Slot> ImageCache::SlotLocked(size_t frame, bool* mine) {
  auto it = slots_.find(frame);
  if (it != slots_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second.second);
    *mine = false;
    return it->second.first;
  }
  auto slot = std::make_shared<Slot>();
  lru_.push_front(frame);
  slots_.emplace(frame, std::make_pair(slot, lru_.begin()));
  *mine = true;
  while (slots_.size() > max_images_) {  // holders keep their slot alive
    slots_.erase(lru_.back());
    lru_.pop_back();
  }
  return slot;
}

void ImageCache::Encode(Slot* slot, size_t frame) {
  try {
    slot->promise.set_value(std::make_shared<const std::string>(encode_(frame)));
  } catch (...) {
    slot->promise.set_exception(std::current_exception());
  }
}

std::shared_ptr<const std::string> ImageCache::Get(size_t frame) {
  std::shared_ptr<Slot> slot;
  bool mine = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    slot = SlotLocked(frame, &mine);
  }
  if (mine) Encode(slot.get(), frame);
  return slot->result.get();  // waits for another thread's encoding; rethrows its error
}

}  // namespace gt::pipeline
