// Encoded colour images of one scene's frames, shared by the samples that the write stage
// computes in parallel (a frame appears in many pairs; decoding, resizing and encoding a
// 640x480 PNG is ~20 ms).
//
// A frame is encoded once: the first request encodes it on the calling thread, and a
// request for a frame that another thread is encoding waits for that result. The encoder
// waits for nothing, so every wait ends. The bytes of an image do not depend on which
// thread encoded it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <future>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

namespace gt::pipeline {

class ImageCache {
 public:
  // encode(frame): the encoded image of a frame (thread-safe; may throw, and the error
  // reaches every request for that frame). Beyond max_images (>= 1) frames, the least
  // recently requested is dropped (its holders keep their copy).
  using Encoder = std::function<std::string(size_t frame)>;
  ImageCache(size_t max_images, Encoder encode);

  // The encoded image of `frame`; rethrows the encoder's error for it.
  std::shared_ptr<const std::string> Get(size_t frame);

 private:
  struct Slot {
    std::promise<std::shared_ptr<const std::string>> promise;
    std::shared_future<std::shared_ptr<const std::string>> result = promise.get_future().share();
  };
  // The slot of `frame`, made (and marked most recent) if new; `mine`: the caller made it and
  // must encode it. Caller holds mutex_.
  std::shared_ptr<Slot> SlotLocked(size_t frame, bool* mine);
  void Encode(Slot* slot, size_t frame);

  size_t max_images_;
  Encoder encode_;
  mutable std::mutex mutex_;
  std::list<size_t> lru_;  // most recent first
  std::map<size_t, std::pair<std::shared_ptr<Slot>, std::list<size_t>::iterator>> slots_;
};

}  // namespace gt::pipeline
