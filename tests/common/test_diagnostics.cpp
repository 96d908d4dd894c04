// Warnings (common/src/diagnostics.cpp): the default handler collects them in order, an
// installed handler receives them instead, and concurrent reports are neither lost nor torn.
#include "flowire/common/diagnostics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <thread>
#include <vector>

#include "flowire_test.hpp"

namespace flowire {
namespace {

/// Takes the test program's handler out (it fails a test on any warning) and puts it back.
class DefaultHandler {
 public:
  DefaultHandler() : saved_(set_warning_handler({})) { (void)take_warnings(); }
  ~DefaultHandler() {
    (void)take_warnings();
    set_warning_handler(std::move(saved_));
  }
  DefaultHandler(const DefaultHandler&) = delete;
  DefaultHandler& operator=(const DefaultHandler&) = delete;

 private:
  WarningHandler saved_;
};

TEST(Diagnostics, TheDefaultHandlerCollectsInOrderAndTakeEmptiesIt) {
  const DefaultHandler guard;
  warn("first");
  warn(std::string("second, ") + "built");
  warn("");
  const auto got = take_warnings();
  EXPECT_EQ(got, (std::vector<std::string>{"first", "second, built", ""}));
  EXPECT_TRUE(take_warnings().empty());
}

TEST(Diagnostics, AnInstalledHandlerReceivesWarningsAndTheDefaultStaysEmpty) {
  const DefaultHandler guard;
  std::vector<std::string> seen;
  const WarningHandler previous = set_warning_handler([&](std::string_view m) { seen.emplace_back(m); });
  EXPECT_FALSE(previous);  // the default was in place
  warn("to the handler");
  EXPECT_EQ(seen, std::vector<std::string>{"to the handler"});
  EXPECT_TRUE(take_warnings().empty());
  // Installing an empty handler restores collection and returns the one that was installed.
  const WarningHandler mine = set_warning_handler({});
  ASSERT_TRUE(mine);
  warn("collected again");
  EXPECT_EQ(seen.size(), 1u);
  EXPECT_EQ(take_warnings(), std::vector<std::string>{"collected again"});
  mine("called directly");
  EXPECT_EQ(seen.back(), "called directly");
}

TEST(Diagnostics, ConcurrentWarningsAreAllCollectedWhole) {
  const DefaultHandler guard;
  constexpr int kThreads = 8, kEach = 500;
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([t] {
      for (int i = 0; i < kEach; ++i) warn("thread " + std::to_string(t) + " warning " + std::to_string(i));
    });
  for (auto& th : threads) th.join();
  auto got = take_warnings();
  ASSERT_EQ(got.size(), static_cast<size_t>(kThreads * kEach));
  std::vector<std::string> expected;
  for (int t = 0; t < kThreads; ++t)
    for (int i = 0; i < kEach; ++i) expected.push_back("thread " + std::to_string(t) + " warning " + std::to_string(i));
  std::sort(got.begin(), got.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(got, expected);
}

TEST(Diagnostics, TheTestProgramsCaptureSeesLibraryWarnings) {
  // The test entry point routes warnings to ExpectWarnings while one is alive.
  testing::ExpectWarnings w;
  warn("expected here");
  EXPECT_TRUE(w.contains("expected here"));
  EXPECT_EQ(w.warnings().size(), 1u);
}

}  // namespace
}  // namespace flowire
