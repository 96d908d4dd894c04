#include "flowire/common/diagnostics.hpp"

#include <mutex>

namespace flowire {
namespace {
std::mutex g_mutex;
std::vector<std::string> g_collected;
WarningHandler g_handler;
}  // namespace

void warn(std::string_view message) {
  std::lock_guard lock(g_mutex);
  if (g_handler) {
    g_handler(message);
  } else {
    g_collected.emplace_back(message);
  }
}

WarningHandler set_warning_handler(WarningHandler handler) {
  std::lock_guard lock(g_mutex);
  auto old = std::move(g_handler);
  g_handler = std::move(handler);
  return old;
}

std::vector<std::string> take_warnings() {
  std::lock_guard lock(g_mutex);
  std::vector<std::string> out;
  out.swap(g_collected);
  return out;
}

}  // namespace flowire
