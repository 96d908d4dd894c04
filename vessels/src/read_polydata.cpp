// .vtp (VTK XML) and .vtk (legacy VTK) poly data files: the container read into PolyData, the
// centerline convention it holds told apart by its arrays, and the length unit: flowire's own
// .vtp is in metres, every other file in the caller's unit (metres if none is given).
#include <optional>
#include <string>

#include "polydata_internal.hpp"
#include "read_internal.hpp"

namespace flowire::vessels::detail {

Centerlines read_polydata_centerlines(const std::string& path, const ReadOptions& opt) {
  const auto pd = read_vtk_polydata(path);
  const bool own = find_array(pd.field_data, "flowire_network") != nullptr;
  const double f = length_factor(opt, own ? std::optional<std::string>("m") : std::nullopt, path);
  auto c = polydata_to_centerlines(pd, opt.merge_tolerance);
  scale(c, f);
  return c;
}

Network read_polydata_network(const std::string& path, const ReadOptions& opt) {
  const auto pd = read_vtk_polydata(path);
  if (find_array(pd.field_data, "flowire_network")) {
    const double f = length_factor(opt, std::string("m"), path);
    return finish(*polydata_to_network(pd), opt, f, path);
  }
  const double f = length_factor(opt, std::nullopt, path);
  auto c = polydata_to_centerlines(pd, opt.merge_tolerance);
  scale(c, f);
  return finish(build_checked(c, opt.build), opt, f, path);
}

}  // namespace flowire::vessels::detail
