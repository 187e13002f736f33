// ImageCache: each frame encoded once, least recently used dropped, encoder errors reach
// every request, and a request for a frame another thread is encoding waits for its result.
#include "libgt/pipeline/image_cache.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace gt::pipeline {
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

// Thread A encodes frame 0; thread B asks for frame 0 meanwhile: it waits for A's result
// and does not encode the frame a second time.
TEST(ImageCache, ARequestForAFrameBeingEncodedWaitsForThatResult) {
  CountingEncoder enc;
  std::mutex mutex;
  std::condition_variable cv;
  bool zero_started = false, release = false;
  ImageCache cache(16, [&](size_t f) {
    std::string bytes = enc(f);
    if (f == 0) {
      std::unique_lock<std::mutex> lock(mutex);
      zero_started = true;
      cv.notify_all();
      cv.wait_for(lock, std::chrono::seconds(10), [&] { return release; });
    }
    return bytes;
  });
  std::shared_ptr<const std::string> a_result, b_result;
  std::thread a([&] { a_result = cache.Get(0); });
  {
    std::unique_lock<std::mutex> lock(mutex);
    cv.wait(lock, [&] { return zero_started; });
  }
  std::thread b([&] { b_result = cache.Get(0); });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // B is waiting now (or soon)
  {
    std::lock_guard<std::mutex> lock(mutex);
    release = true;
  }
  cv.notify_all();
  b.join();
  a.join();
  ASSERT_TRUE(a_result && b_result);
  EXPECT_EQ(*a_result, "image 0");
  EXPECT_EQ(*b_result, "image 0");
  EXPECT_EQ(enc.calls[0], 1);
}

// Many threads asking for overlapping frames: every result is right and
// every frame is encoded exactly once (nothing is dropped: the cache holds them all).
TEST(ImageCache, ConcurrentRequestsGetTheRightImagesEachEncodedOnce) {
  CountingEncoder enc;
  ImageCache cache(1000, [&](size_t f) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    return enc(f);
  });
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
}  // namespace gt::pipeline
