// The heap settings fibra and its benchmarks run with (fibra/core/heap.hpp).
#include <gtest/gtest.h>
#include <malloc.h>

#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>

#include "fibra/core/heap.hpp"

namespace {

/// Unsets an environment variable for the scope of a test and puts it back afterwards.
class EnvUnset {
 public:
  explicit EnvUnset(const char* name) : name_(name) {
    if (const char* v = std::getenv(name)) old_ = v;
    unsetenv(name);
  }
  ~EnvUnset() {
    if (old_) setenv(name_, old_->c_str(), 1);
  }
  EnvUnset(const EnvUnset&) = delete;
  EnvUnset& operator=(const EnvUnset&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// AddressSanitizer replaces malloc (the sanitized build, docs/sanitizers.md): glibc's settings
// and counters do not exist there.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

constexpr const char* kTuned[] = {"GLIBC_TUNABLES", "MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_",
                                  "MALLOC_TOP_PAD_", "MALLOC_MMAP_MAX_"};

// A user who tunes malloc keeps their settings: each of the variables alone stops the call.
TEST(Heap, LeftAloneWhenTheUserTunesMalloc) {
  for (const char* tuned : kTuned) {
    SCOPED_TRACE(tuned);
    EnvUnset a(kTuned[0]), b(kTuned[1]), c(kTuned[2]), d(kTuned[3]), e(kTuned[4]);
    setenv(tuned, "1", 1);
    EXPECT_FALSE(fibra::keep_freed_memory());
    unsetenv(tuned);
  }
}

// Once set, a 64 MB block (above glibc's default 32 MB ceiling of its mapping threshold) comes
// from the heap, not from a fresh mapping, and its memory stays in the heap after free().
TEST(Heap, LargeBlocksComeFromTheHeapAndStay) {
  if (kSanitized) GTEST_SKIP() << "AddressSanitizer's allocator replaces glibc's";
  EnvUnset a(kTuned[0]), b(kTuned[1]), c(kTuned[2]), d(kTuned[3]), e(kTuned[4]);
  ASSERT_TRUE(fibra::keep_freed_memory());
  constexpr std::size_t size = 64u << 20;
  const std::size_t mapped_before = mallinfo2().hblkhd;
  void* block = std::malloc(size);
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, size);
  EXPECT_EQ(mallinfo2().hblkhd, mapped_before) << "the block was mapped on its own";
  std::free(block);
  EXPECT_GE(mallinfo2().arena, size) << "the freed block went back to the system";
}

// A block above 2 GB (past the largest mapping threshold mallopt takes) comes from the heap too,
// and the heap keeps the memory a freed block leaves at its top even when that is over 2 GB: a
// 480-fiber factor freed and allocated again is not faulted in again page by page. The blocks
// are never touched, so they cost address space, not memory.
TEST(Heap, BlocksOfOverTwoGigabytesComeFromTheHeapAndStay) {
  if (kSanitized) GTEST_SKIP() << "AddressSanitizer's allocator replaces glibc's";
  EnvUnset a(kTuned[0]), b(kTuned[1]), c(kTuned[2]), d(kTuned[3]), e(kTuned[4]);
  ASSERT_TRUE(fibra::keep_freed_memory());
  for (const std::size_t size : {std::size_t{3} << 30, (std::size_t{2} << 30) - (std::size_t{1} << 20)}) {
    SCOPED_TRACE(size);
    const std::size_t mapped_before = mallinfo2().hblkhd;
    void* block = std::malloc(size);
    ASSERT_NE(block, nullptr);
    EXPECT_EQ(mallinfo2().hblkhd, mapped_before) << "the block was mapped on its own";
    std::free(block);
    EXPECT_GE(mallinfo2().arena, size) << "the freed block went back to the system";
  }
}

}  // namespace
