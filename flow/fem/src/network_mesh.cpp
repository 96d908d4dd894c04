// The lumen of a vessel network as fused OpenCASCADE solids, meshed by gmsh into
// quadratic tetrahedra (see network_mesh.hpp for the geometry rules and the checks): the
// pieces and spheres of the network and their checks, then the solids, the end faces
// tagged as inlet and outlets, and the size field.
#include "flowire/flow/fem/network_mesh.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>
#include <string>
#include <unordered_map>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/mesh/extract.hpp"
#include "flowire/mesh/gmsh_session.hpp"
#include "flowire/mesh/network_solids.hpp"
#include "flowire/vessels/spatial.hpp"
#include "mesh_broadcast.hpp"

namespace flowire::flow::fem {
namespace {

std::string where(const Network& net) {
  return net.source().empty() ? std::string("fem geometry") : fmt::format("fem geometry of {}", net.source());
}

using mesh::extract_mesh;
using mesh::generate;
using mesh::GmshModel;
using mesh::tag_groups_and_set_options;

TetMesh mesh_geometry(const Network& net, const mesh::NetworkSolids& g, const MeshOptions& opt) {
  const auto start = std::chrono::steady_clock::now();
  const std::string at = where(net);
  const std::vector<int> ends = net.ends();
  const int inlet = opt.inlet_node >= 0 ? opt.inlet_node : net.widest_end();
  if (std::find(ends.begin(), ends.end(), inlet) == ends.end())
    throw_input_error(at, fmt::format("inlet node {} is not a network end", inlet));
  if (ends.size() < 2) throw_input_error(at, "the network needs an inlet and at least one outlet");

  TetMesh mesh;
  mesh.groups.push_back({BoundaryGroup::Kind::Wall, -1, "wall"});
  mesh.groups.push_back({BoundaryGroup::Kind::Inlet, inlet, "inlet"});
  for (int e : ends)
    if (e != inlet) mesh.groups.push_back({BoundaryGroup::Kind::Outlet, e, fmt::format("outlet_{}", e)});

  GmshModel model(opt.verbose);
  namespace occ = gmsh::model::occ;
  (void)mesh::add_network_solids(net, g, [](double r, int) { return r; });
  occ::synchronize();
  gmsh::vectorpair vols, surfs;
  gmsh::model::getEntities(vols, 3);
  if (vols.size() != 1)
    throw_input_error(
        at, fmt::format("the fused lumen is {} separate volumes, not one; is the network connected?", vols.size()));
  gmsh::model::getEntities(surfs, 2);
  // End faces: planar faces centred on the end nodes.
  std::vector<int> surf_group(surfs.size(), 0);
  for (size_t gi = 1; gi < mesh.groups.size(); ++gi) {
    const int node = mesh.groups[gi].node;
    const Vec3 x = net.node(node);
    const double r = net.segment(*net.node_segments(node).first).radius;
    int found = -1;
    for (size_t k = 0; k < surfs.size(); ++k) {
      std::string type;
      gmsh::model::getType(2, surfs[k].second, type);
      if (type != "Plane") continue;
      double cx = 0, cy = 0, cz = 0;
      occ::getCenterOfMass(2, surfs[k].second, cx, cy, cz);
      if ((Vec3(cx, cy, cz) - x).norm() <= 1e-3 * r) found = static_cast<int>(k);
    }
    if (found < 0)
      throw_input_error(at, fmt::format("end node {}: its end face was not found after fusing (another vessel "
                                        "or a junction sphere covers it)",
                                        node));
    surf_group[static_cast<size_t>(found)] = static_cast<int>(gi);
  }
  tag_groups_and_set_options(vols[0].second, "lumen", mesh.groups, surfs, surf_group, opt.algorithm3d);
  // Sizes: fixed, or a fraction of the radius of the nearest piece.
  double hmin = std::numeric_limits<double>::infinity();
  for (const mesh::NetworkPiece& p : g.pieces) hmin = std::min(hmin, opt.size_factor * p.radius);
  if (!mesh::set_size_bounds(opt.mesh_size, opt.size_factor)) {
    const mesh::NetworkSolids* geo = &g;
    const Network* nw = &net;
    const double factor = opt.size_factor;
    gmsh::model::mesh::setSizeCallback([geo, nw, factor](int, int, double x, double y, double z) {
      const Vec3 p(x, y, z);
      double best = std::numeric_limits<double>::infinity(), r = geo->pieces.front().radius;
      for (const mesh::NetworkPiece& pc : geo->pieces) {
        const double d = vessels::project_on_axis(p, nw->node(pc.a), nw->node(pc.b)).distance - pc.radius;
        if (d < best) {
          best = d;
          r = pc.radius;
        }
      }
      return factor * r;
    });
  }
  generate(opt);
  extract_mesh(mesh, surfs, surf_group, at);
  mesh.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return mesh;
}

}  // namespace

TetMesh build_mesh(const Network& net, const MeshOptions& opt) {
  return detail::build_shared([&] {
    const mesh::NetworkSolids g = mesh::make_network_solids(net, where(net));
    return mesh::guarded(where(net), [&] { return mesh_geometry(net, g, opt); });
  });
}

}  // namespace flowire::flow::fem
