#include "libgt/pairs/image_cache.h"

#include <chrono>
#include <stdexcept>

namespace gt::pairs {

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

bool ImageCache::EncodeOneExpected() {
  std::shared_ptr<Slot> slot;
  size_t frame = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    while (!expected_.empty() && !slot) {
      frame = expected_.front();
      expected_.pop_front();
      if (slots_.count(frame) != 0) continue;  // encoded or being encoded
      bool mine = false;
      slot = SlotLocked(frame, &mine);
      ++encoded_while_waiting_;
    }
  }
  if (!slot) return false;
  Encode(slot.get(), frame);
  return true;
}

std::shared_ptr<const std::string> ImageCache::Get(size_t frame) {
  std::shared_ptr<Slot> slot;
  bool mine = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    slot = SlotLocked(frame, &mine);
  }
  if (mine) {
    Encode(slot.get(), frame);
  } else {
    while (slot->result.wait_for(std::chrono::seconds(0)) != std::future_status::ready &&
           EncodeOneExpected()) {
    }
  }
  return slot->result.get();  // rethrows the encoder's error
}

void ImageCache::Expect(size_t frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Entries already started are dropped from the front, so that the queue stays short when
  // every frame is encoded by the sample that needs it first.
  while (!expected_.empty() && slots_.count(expected_.front()) != 0) expected_.pop_front();
  if (slots_.count(frame) == 0) expected_.push_back(frame);
}

int64_t ImageCache::encoded_while_waiting() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return encoded_while_waiting_;
}

}  // namespace gt::pairs
