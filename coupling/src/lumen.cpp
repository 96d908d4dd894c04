#include "flowire/coupling/lumen.hpp"

#include "flowire/common/error.hpp"
#include "flowire/common/units.hpp"

namespace flowire::coupling {

std::unique_ptr<vessels::LumenSurface> make_scene_surface(const config::Config& c, const vessels::Network& net,
                                                          nlohmann::json& info, double& smoothing) {
  if (!c.has("vessels.surface")) return nullptr;
  const std::string unit = c.string_or("vessels.length_unit", "m");
  const double factor = units::length_unit_factor(unit.empty() ? "m" : unit, c.where("vessels.length_unit"));
  auto mesh = vessels::read_surface(c.resolve_path(c.string("vessels.surface")), factor);
  std::vector<vessels::VesselEnd> ends;
  std::vector<vessels::Vec3> inside;
  for (int i = 0; i < net.num_nodes(); ++i) {
    if (net.degree(i) != 1) {
      inside.push_back(net.node(i));
      continue;
    }
    const auto& seg = net.segment(*net.node_segments(i).first);
    const double r = (seg.node_from == i ? seg.radius_from : seg.radius_to) > 0.0
                         ? (seg.node_from == i ? seg.radius_from : seg.radius_to)
                         : seg.radius;
    // The vessel's direction at its end: from a node at least two radii back along the
    // branch (the last segments may be short and their direction noisy).
    int prev = i, at = seg.node_from == i ? seg.node_to : seg.node_from, via = *net.node_segments(i).first;
    while ((net.node(at) - net.node(i)).norm() < 2.0 * r && net.degree(at) == 2) {
      const auto [b, e] = net.node_segments(at);
      const int next_seg = b[0] == via ? b[1] : b[0];
      const auto& ns = net.segment(next_seg);
      prev = at;
      at = ns.node_from == at ? ns.node_to : ns.node_from;
      via = next_seg;
    }
    (void)prev;
    ends.push_back({net.node(i), (net.node(i) - net.node(at)).normalized(), r});
  }
  const int caps = vessels::remove_end_caps(mesh, ends);
  auto s = std::make_unique<vessels::LumenSurface>(std::move(mesh), inside);
  const auto& k = s->counts();
  info = {{"file", c.string("vessels.surface")},
          {"triangles", k.triangles},
          {"cap_triangles_removed", caps},
          {"boundary_loops", k.boundary_loops},
          {"components", k.components},
          {"nonmanifold_edges", k.nonmanifold_edges},
          {"mean_edge", k.mean_edge}};
  smoothing =
      c.has("vessels.surface_smoothing") ? c.number("vessels.surface_smoothing") : default_surface_smoothing(*s);
  if (!(smoothing >= 0.0)) throw_input_error(c.where("vessels.surface_smoothing"), "must be >= 0");
  info["smoothing"] = smoothing;
  return s;
}

double default_surface_smoothing(const vessels::LumenSurface& surface) { return 0.4 * surface.counts().mean_edge; }

}  // namespace flowire::coupling
