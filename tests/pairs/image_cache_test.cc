// ImageCache: each frame encoded once, least recently used dropped, encoder errors reach
// every request, and a request for a frame another thread is encoding encodes the expected
// frames nobody has started instead of sleeping.
#include "libgt/pairs/image_cache.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace gt::pairs {
namespace {

// Counts encodes per frame and the thread of each; "image <frame>" is the encoded image.
struct CountingEncoder {
  std::mutex mutex;
  std::map<size_t, int> calls;
  std::map<size_t, std::thread::id> thread_of;
  std::string operator()(size_t frame) {
    std::lock_guard<std::mutex> lock(mutex);
    ++calls[frame];
    thread_of[frame] = std::this_thread::get_id();
    return "image " + std::to_string(frame);
  }
};

TEST(ImageCache, EncodesEachFrameOnceAndDropsTheLeastRecentlyUsed) {
  CountingEncoder enc;
  ImageCache cache(2, [&](size_t f) { return enc(f); });
  EXPECT_EQ(*cache.Get(7), "image 7");
  EXPECT_EQ(*cache.Get(7), "image 7");
  EXPECT_EQ(*cache.Get(8), "image 8");
  EXPECT_EQ(enc.calls[7], 1);
  EXPECT_EQ(*cache.Get(7), "image 7");  // 7 most recent: 8 is dropped next
  EXPECT_EQ(*cache.Get(9), "image 9");
  EXPECT_EQ(*cache.Get(7), "image 7");
  EXPECT_EQ(enc.calls[7], 1);
  EXPECT_EQ(*cache.Get(8), "image 8");
  EXPECT_EQ(enc.calls[8], 2);
  EXPECT_EQ(cache.encoded_while_waiting(), 0);
}

TEST(ImageCache, AnEncoderErrorReachesEveryRequestOfThatFrame) {
  int calls = 0;
  ImageCache cache(4, [&](size_t f) -> std::string {
    ++calls;
    if (f == 3) throw std::runtime_error("frame 3: unreadable");
    return "ok";
  });
  EXPECT_THROW(cache.Get(3), std::runtime_error);
  EXPECT_THROW(cache.Get(3), std::runtime_error);
  EXPECT_EQ(*cache.Get(4), "ok");
  EXPECT_EQ(calls, 2);
}

TEST(ImageCache, RejectsBadOptions) {
  EXPECT_THROW(ImageCache(0, [](size_t) { return std::string(); }), std::invalid_argument);
  EXPECT_THROW(ImageCache(4, nullptr), std::invalid_argument);
}

// Thread A encodes frame 0, and its encoder returns only once frames 1 and 2 are encoded
// (or after 10 s, so that a cache that sleeps instead fails the test rather than hanging
// it). Thread B asks for frame 0 meanwhile: it must encode the expected frames 1 and 2
// itself, pass over the ones already encoded or started (5, 0), then get A's frame 0.
TEST(ImageCache, ARequestWaitingForAnotherThreadEncodesTheExpectedFrames) {
  CountingEncoder enc;
  std::mutex mutex;
  std::condition_variable cv;
  bool zero_started = false;
  int helpers_done = 0;
  ImageCache cache(16, [&](size_t f) {
    std::string bytes = enc(f);
    std::unique_lock<std::mutex> lock(mutex);
    if (f == 0) {
      zero_started = true;
      cv.notify_all();
      cv.wait_for(lock, std::chrono::seconds(10), [&] { return helpers_done == 2; });
    } else if (f == 1 || f == 2) {
      ++helpers_done;
      cv.notify_all();
    }
    return bytes;
  });
  EXPECT_EQ(*cache.Get(5), "image 5");
  for (size_t f : {size_t{5}, size_t{0}, size_t{1}, size_t{2}}) cache.Expect(f);

  std::shared_ptr<const std::string> a_result, b_result;
  std::thread a([&] { a_result = cache.Get(0); });
  {
    std::unique_lock<std::mutex> lock(mutex);
    cv.wait(lock, [&] { return zero_started; });
  }
  std::thread b([&] { b_result = cache.Get(0); });
  const std::thread::id b_id = b.get_id();
  b.join();
  a.join();

  ASSERT_TRUE(a_result && b_result);
  EXPECT_EQ(*a_result, "image 0");
  EXPECT_EQ(*b_result, "image 0");
  EXPECT_EQ(cache.encoded_while_waiting(), 2);
  EXPECT_EQ(enc.thread_of[1], b_id);
  EXPECT_EQ(enc.thread_of[2], b_id);
  for (size_t f : {size_t{0}, size_t{1}, size_t{2}, size_t{5}}) {
    EXPECT_EQ(*cache.Get(f), "image " + std::to_string(f));
    EXPECT_EQ(enc.calls[f], 1) << "frame " << f;
  }
}

// Many threads asking for overlapping frames with expectations: every result is right and
// every frame is encoded exactly once (nothing is dropped: the cache holds them all).
TEST(ImageCache, ConcurrentRequestsGetTheRightImagesEachEncodedOnce) {
  CountingEncoder enc;
  ImageCache cache(1000, [&](size_t f) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    return enc(f);
  });
  for (size_t f = 0; f < 64; ++f) cache.Expect(f);
  std::vector<std::thread> threads;
  std::vector<int> wrong(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (size_t k = 0; k < 64; ++k) {
        const size_t f = (k + static_cast<size_t>(t) * 5) % 64;
        if (*cache.Get(f) != "image " + std::to_string(f)) ++wrong[t];
      }
    });
  }
  for (auto& t : threads) t.join();
  for (int t = 0; t < 4; ++t) EXPECT_EQ(wrong[t], 0);
  for (size_t f = 0; f < 64; ++f) EXPECT_EQ(enc.calls[f], 1) << "frame " << f;
}

}  // namespace
}  // namespace gt::pairs
