// Encoded colour images of one scene's frames, shared by the samples that the write stage
// computes in parallel (a frame appears in many pairs; decoding, resizing and encoding a
// 640x480 PNG is ~20 ms).
//
// A frame is encoded once: the first request encodes it on the calling thread, and a
// request for a frame that another thread is encoding gets that result. Such a request
// does not sleep while there is other encoding to do: it encodes, one after the other, the
// frames announced with Expect() that nobody has started (the frames of the samples about
// to be computed), until the image it needs is ready; only then does it wait. With two
// threads the wait was ~26 ms of an idle core in every tartanair-sample build
// (docs/PERFORMANCE.md). The encoder waits for nothing, so every wait ends. The bytes of
// an image do not depend on which thread encoded it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <future>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

namespace gt::pairs {

class ImageCache {
 public:
  // encode(frame): the encoded image of a frame (thread-safe; may throw, and the error
  // reaches every request for that frame). Beyond max_images (>= 1) frames, the least
  // recently requested is dropped (its holders keep their copy).
  using Encoder = std::function<std::string(size_t frame)>;
  ImageCache(size_t max_images, Encoder encode);

  // The encoded image of `frame`; rethrows the encoder's error for it.
  std::shared_ptr<const std::string> Get(size_t frame);

  // `frame` will be requested soon: a waiting Get may encode it (calls in the order of first
  // use; a frame already encoded or started is passed over).
  void Expect(size_t frame);

  // Frames encoded by a Get while it waited for another thread's encoding of its own frame.
  int64_t encoded_while_waiting() const;

 private:
  struct Slot {
    std::promise<std::shared_ptr<const std::string>> promise;
    std::shared_future<std::shared_ptr<const std::string>> result = promise.get_future().share();
  };
  // The slot of `frame`, made (and marked most recent) if new; `mine`: the caller made it and
  // must encode it. Caller holds mutex_.
  std::shared_ptr<Slot> SlotLocked(size_t frame, bool* mine);
  void Encode(Slot* slot, size_t frame);
  // Encodes the first expected frame that has no slot; false when there is none.
  bool EncodeOneExpected();

  size_t max_images_;
  Encoder encode_;
  mutable std::mutex mutex_;
  std::list<size_t> lru_;  // most recent first
  std::map<size_t, std::pair<std::shared_ptr<Slot>, std::list<size_t>::iterator>> slots_;
  std::deque<size_t> expected_;
  int64_t encoded_while_waiting_ = 0;
};

}  // namespace gt::pairs
