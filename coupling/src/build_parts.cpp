// Which of a scene's parts this build of the library lacks (compiled into each variant of the
// library with that variant's FLOWIRE_HAVE_SOLID / FLOWIRE_HAVE_FEM / FLOWIRE_WITH_PETSC).
#include "flowire/coupling/scene.hpp"

namespace flowire::coupling {

std::vector<std::string> unbuilt_scene_parts(const config::Config& c) {
  std::vector<std::string> parts;
#ifndef FLOWIRE_HAVE_SOLID
  if (c.has_section("wall")) parts.emplace_back("wall");
#endif
#ifndef FLOWIRE_HAVE_FEM
  if (c.has_section("fem")) parts.emplace_back("fem");
#endif
#ifndef FLOWIRE_WITH_PETSC
  if (c.has_section("flow") && c.string("flow.solver") == "petsc") parts.emplace_back("flow.solver: petsc");
#endif
  (void)c;
  return parts;
}

}  // namespace flowire::coupling
