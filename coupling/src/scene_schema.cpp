// The declaration of every scene key, composed section by section: each section's keys are
// declared next to the code that reads them (scene_sections.hpp lists where).
// docs/scene-keys.md is generated from it (`flowire help scene`).
#include <fmt/format.h>

#include <map>
#include <string>
#include <string_view>

#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/flow/spec.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

namespace {

config::Schema make_schema() {
  config::Schema s;
  s.add("name", config::Type::String, "", units::Dimension::None, "a name for the scene, copied to summary.json");
  declare_vessel_keys(s);
  flow::declare_scene_keys(s);
  declare_wire_keys(s);
  declare_catheter_keys(s);
  declare_load_keys(s);
  declare_insertion_keys(s);
  declare_contact_keys(s);
  declare_obstacle_keys(s);
  declare_coupling_keys(s);
  declare_solve_keys(s);
  declare_fem_keys(s);
  declare_wall_keys(s);
  declare_output_keys(s);
  return s;
}

}  // namespace

const config::Schema& scene_schema() {
  static const config::Schema schema = make_schema();
  return schema;
}

const config::Config& declared_scene_defaults(std::string_view section) {
  // Every top-level section's declared defaults, made once.
  static const std::map<std::string, config::Config, std::less<>> declared = [] {
    std::map<std::string, config::Config, std::less<>> m;
    for (const config::Key* k : scene_schema().children(""))
      if (k->type == config::Type::Section) m.emplace(k->path, config::declared_defaults(scene_schema(), k->path));
    return m;
  }();
  const auto it = declared.find(section);
  if (it == declared.end())
    throw_usage_error(fmt::format("declared_scene_defaults: '{}' is no top-level section", section));
  return it->second;
}

const config::Config& given_or_declared(const config::Config& scene, std::string_view section) {
  return scene.has_section(section) ? scene : declared_scene_defaults(section);
}

}  // namespace flowire::coupling
