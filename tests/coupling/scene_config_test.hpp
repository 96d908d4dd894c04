#pragma once
// Helpers for the tests of the scene's sections (coupling/src/config_*.cpp): a scene from
// YAML text, the keys a section declares, and the input error a reader throws.
#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <vector>

#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"

namespace flowire::coupling::test {

/// A scene read from @p yaml as if from the file scene.yaml.
inline config::Config scene(const std::string& yaml) {
  return config::load_config_text(yaml, "scene.yaml", scene_schema());
}

/// The paths a section's declare function declares, in order.
template <class Declare>
std::vector<std::string> declared_paths(Declare declare) {
  config::Schema s;
  declare(s);
  std::vector<std::string> paths;
  for (const auto& k : s.keys()) paths.push_back(k.path);
  return paths;
}

/// Every path in @p paths starts with one of @p sections and has the declaration of the
/// whole scene (same type, default and doc: the scene composes the section unchanged).
inline void expect_section_of_scene(const std::vector<std::string>& paths, std::vector<std::string_view> sections) {
  ASSERT_FALSE(paths.empty());
  for (const auto& p : paths) {
    bool under = false;
    for (auto s : sections)
      under = under || p == s || p.starts_with(std::string(s) + ".") || p.starts_with(std::string(s) + "[");
    EXPECT_TRUE(under) << p << " is outside its section";
    EXPECT_NE(scene_schema().find(p), nullptr) << p << " is not in the scene's declaration";
  }
}

/// The message of the input error @p f throws (empty, and a test failure, if it throws none).
template <class F>
std::string input_error(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no input error was thrown";
  return {};
}

}  // namespace flowire::coupling::test
