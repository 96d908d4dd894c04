// Test entry point shared by every flowire test program: any warning a library reports
// during a test fails that test, unless the test captures it with ExpectWarnings.
#include <gtest/gtest.h>

#include <string>
#include <string_view>

#include "flowire/common/diagnostics.hpp"
#include "flowire_test.hpp"

namespace flowire::testing {
namespace {
int g_capture_depth = 0;
std::vector<std::string>* g_captured = nullptr;
}  // namespace

ExpectWarnings::ExpectWarnings() : previous_(g_captured) {
  ++g_capture_depth;
  g_captured = &captured_;
}
ExpectWarnings::~ExpectWarnings() {
  --g_capture_depth;
  g_captured = previous_;
}

bool ExpectWarnings::contains(std::string_view fragment) const {
  for (const auto& w : captured_)
    if (w.find(fragment) != std::string::npos) return true;
  return false;
}

}  // namespace flowire::testing

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  flowire::set_warning_handler([](std::string_view msg) {
    if (flowire::testing::g_captured) {
      flowire::testing::g_captured->emplace_back(msg);
      return;
    }
    ADD_FAILURE() << "library reported a warning: " << msg;
  });
  return RUN_ALL_TESTS();
}
