// A real lumen surface meshed by gmsh: open ends found (or a closed surface's flat caps),
// capped, matched to the centerline ends, classified into patches and meshed into
// quadratic tetrahedra (see lumen.hpp).
#include "flowire/flow/fem/lumen.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <numbers>
#include <numeric>
#include <unordered_map>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/flow/fem/element.hpp"
#include "flowire/mesh/extract.hpp"
#include "flowire/mesh/gmsh_session.hpp"
#include "flowire/vessels/surface.hpp"
#include "mesh_broadcast.hpp"

#ifdef FLOWIRE_HAVE_VTK
#include <vtkAlgorithm.h>
#include <vtkCellArray.h>
#include <vtkCleanPolyData.h>
#include <vtkNew.h>
#include <vtkOBJReader.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>
#include <vtkSTLReader.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>
#include <vtkXMLPolyDataReader.h>
#endif

namespace flowire::flow::fem {
namespace {

using vessels::mm;

/// The angle between two faces' normals beyond which gmsh splits patches (the cap rims), and
/// the rim angle below which an open end is cut again square (a margin above it).
constexpr double kCreaseAngle = 40.0 * std::numbers::pi / 180.0;
constexpr double kRimAngle = 45.0 * std::numbers::pi / 180.0;

std::string lower_extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

/// Signed volume enclosed by a closed triangulation (divergence theorem).
double signed_volume(const SurfaceMesh& s) {
  double v = 0.0;
  for (const auto& t : s.triangles)
    v += s.points[static_cast<size_t>(t[0])].dot(
             s.points[static_cast<size_t>(t[1])].cross(s.points[static_cast<size_t>(t[2])])) /
         6.0;
  return v;
}

struct EdgeUse {
  int count = 0;
  int from = -1, to = -1;  // oriented as in the first triangle that uses it
};

std::unordered_map<std::uint64_t, EdgeUse> edge_uses(const SurfaceMesh& s) {
  std::unordered_map<std::uint64_t, EdgeUse> uses;
  uses.reserve(s.triangles.size() * 2);
  for (const auto& t : s.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[static_cast<size_t>(k)], b = t[static_cast<size_t>((k + 1) % 3)];
      EdgeUse& u = uses[edge_key(a, b)];
      if (u.count++ == 0) {
        u.from = a;
        u.to = b;
      }
    }
  for (const auto& [key, u] : uses)
    if (u.count > 2)
      throw_input_error(fmt::format("{}: edge {} - {}", s.source, mm(s.points[static_cast<size_t>(u.from)]),
                                    mm(s.points[static_cast<size_t>(u.to)])),
                        fmt::format("is shared by {} triangles (the surface is not a manifold); repair it", u.count));
  return uses;
}

/// Cut the surface by the plane through `origin` normal to `out` (pointing out of the
/// lumen) near `origin`: triangles with a vertex within `reach` of it lose their part beyond
/// the plane (split where they cross it; the cut points are shared, so the result stays
/// conforming). Returns the number of triangles touched.
int clip_end(SurfaceMesh& s, const Vec3& origin, const Vec3& out, double reach, double eps) {
  return vessels::clip_surface(s.points, s.triangles, origin, out, reach, eps);
}

/// Closed surface without flat caps (an image's level set rounded at its ends): cut every
/// vessel end by the plane normal to the centerline `back` end radii before its end node.
void clip_ends(SurfaceMesh& s, const Network& net, double back) {
  for (int e : net.ends()) {
    const int seg = *net.node_segments(e).first;
    const auto& sg = net.segment(seg);
    const int other = sg.node_from == e ? sg.node_to : sg.node_from;
    const Vec3 out = (net.node(e) - net.node(other)).normalized();
    const double r = sg.radius;
    clip_end(s, net.node(e) - back * r * out, out, (2.5 + back) * r, 1e-6 * r);
  }
}

/// The loops of boundary edges, each oriented as its triangles run.
std::vector<std::vector<int>> boundary_loops(const SurfaceMesh& s) {
  const auto uses = edge_uses(s);
  std::unordered_map<int, int> next;
  for (const auto& [key, u] : uses) {
    if (u.count != 1) continue;
    if (!next.emplace(u.from, u.to).second)
      throw_input_error(fmt::format("{}: point {}", s.source, mm(s.points[static_cast<size_t>(u.from)])),
                        "two open ends touch here (a boundary point on two open loops); repair the surface");
  }
  std::vector<std::vector<int>> loops;
  std::unordered_map<int, char> done;
  for (const auto& [start, unused] : next) {
    if (done.count(start)) continue;
    std::vector<int> loop;
    int v = start;
    while (!done.count(v)) {
      done[v] = 1;
      loop.push_back(v);
      const auto it = next.find(v);
      if (it == next.end())
        throw_input_error(fmt::format("{}: point {}", s.source, mm(s.points[static_cast<size_t>(v)])),
                          "an open end does not close into a loop; repair the surface");
      v = it->second;
    }
    if (v != start)
      throw_input_error(fmt::format("{}: point {}", s.source, mm(s.points[static_cast<size_t>(v)])),
                        "open ends meet here; repair the surface");
    loops.push_back(std::move(loop));
  }
  // A fixed order (by the smallest point index) so that the same file gives the same mesh.
  std::sort(loops.begin(), loops.end(), [](const auto& a, const auto& b) {
    return *std::min_element(a.begin(), a.end()) < *std::min_element(b.begin(), b.end());
  });
  return loops;
}

/// The sharpest rim of an open end: the smallest angle between a wall triangle on the loop and
/// the cap's fan triangle on the same edge (both oriented as the surface), in radians. Where it
/// is small the cap nearly continues the wall (an end cut obliquely) and the patches cannot be
/// told apart at the rim.
double rim_angle(const SurfaceMesh& s, const std::vector<int>& loop) {
  std::unordered_map<std::uint64_t, Vec3> wall_normal;
  std::unordered_map<std::uint64_t, char> on_loop;
  const size_t n = loop.size();
  for (size_t i = 0; i < n; ++i) on_loop[edge_key(loop[i], loop[(i + 1) % n])] = 1;
  for (const auto& t : s.triangles)
    for (int k = 0; k < 3; ++k) {
      const auto key = edge_key(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)]);
      if (!on_loop.count(key)) continue;
      const Vec3& a = s.points[static_cast<size_t>(t[0])];
      wall_normal[key] = (s.points[static_cast<size_t>(t[1])] - a).cross(s.points[static_cast<size_t>(t[2])] - a);
    }
  Vec3 centroid = Vec3::Zero();
  for (int v : loop) centroid += s.points[static_cast<size_t>(v)];
  centroid /= static_cast<double>(n);
  double sharpest = std::numbers::pi;
  for (size_t i = 0; i < n; ++i) {
    const Vec3& a = s.points[static_cast<size_t>(loop[i])];
    const Vec3& b = s.points[static_cast<size_t>(loop[(i + 1) % n])];
    const Vec3 fan = (b - centroid).cross(a - centroid);  // (centre, b, a), as the caps are made
    const auto it = wall_normal.find(edge_key(loop[i], loop[(i + 1) % n]));
    if (it == wall_normal.end() || fan.norm() == 0.0 || it->second.norm() == 0.0) continue;
    const double c = std::clamp(fan.normalized().dot(it->second.normalized()), -1.0, 1.0);
    sharpest = std::min(sharpest, std::acos(c));
  }
  return sharpest;
}

/// Open ends cut so obliquely that the wall meets their cap at less than `min_angle`: each cut
/// again by the plane normal to its centerline just inside the loop's innermost point (all of
/// the old loop beyond it), which leaves a planar open end square to the vessel. Returns the
/// number of ends cut.
int recut_oblique_ends(SurfaceMesh& s, const Network& net, const std::vector<std::vector<int>>& loops,
                       double min_angle) {
  int cut = 0;
  for (const auto& loop : loops) {
    if (rim_angle(s, loop) >= min_angle) continue;
    Vec3 centroid = Vec3::Zero();
    for (int v : loop) centroid += s.points[static_cast<size_t>(v)];
    centroid /= static_cast<double>(loop.size());
    int e = -1;
    for (int end : net.ends())
      if (e < 0 || (net.node(end) - centroid).norm() < (net.node(e) - centroid).norm()) e = end;
    const auto& sg = net.segment(*net.node_segments(e).first);
    const int other = sg.node_from == e ? sg.node_to : sg.node_from;
    const Vec3 out = (net.node(e) - net.node(other)).normalized();
    double innermost = std::numeric_limits<double>::infinity();
    for (int v : loop) innermost = std::min(innermost, (s.points[static_cast<size_t>(v)] - net.node(e)).dot(out));
    const Vec3 origin = net.node(e) + (innermost - 0.1 * sg.radius) * out;
    double reach = 0.0;
    for (int v : loop) reach = std::max(reach, (s.points[static_cast<size_t>(v)] - origin).norm());
    clip_end(s, origin, out, reach + sg.radius, 1e-6 * sg.radius);
    ++cut;
  }
  return cut;
}

double end_radius(const Network& net, int e) { return net.segment(*net.node_segments(e).first).radius; }

}  // namespace

SurfaceMesh read_surface(const std::string& path, double length_factor) {
  if (!(length_factor > 0.0)) throw_usage_error("read_surface: the length factor must be > 0");
  check_input_file(path, input_limit::kGeometry, "a lumen surface");
  SurfaceMesh s;
  s.source = path;
#ifdef FLOWIRE_HAVE_VTK
  const std::string ext = lower_extension(path);
  vtkSmartPointer<vtkAlgorithm> reader;
  if (ext == ".stl") {
    auto r = vtkSmartPointer<vtkSTLReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  } else if (ext == ".vtp") {
    auto r = vtkSmartPointer<vtkXMLPolyDataReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  } else if (ext == ".obj") {
    auto r = vtkSmartPointer<vtkOBJReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  } else if (ext == ".vtk") {
    auto r = vtkSmartPointer<vtkPolyDataReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  } else {
    throw_input_error(path, "a lumen surface must be .stl, .vtp, .obj or legacy .vtk polydata");
  }
  const int shown = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  reader->Update();
  vtkNew<vtkTriangleFilter> tri;
  tri->SetInputConnection(reader->GetOutputPort());
  tri->PassVertsOff();
  tri->PassLinesOff();
  vtkNew<vtkCleanPolyData> clean;
  clean->SetInputConnection(tri->GetOutputPort());
  clean->ToleranceIsAbsoluteOn();
  clean->SetAbsoluteTolerance(0.0);
  clean->Update();
  vtkObject::SetGlobalWarningDisplay(shown);
  vtkPolyData* pd = clean->GetOutput();
  if (!pd || pd->GetNumberOfPoints() == 0 || pd->GetNumberOfPolys() == 0)
    throw_input_error(path, "the surface has no triangles (empty, unreadable, or not a polygonal surface)");
  s.points.resize(static_cast<size_t>(pd->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < pd->GetNumberOfPoints(); ++i) {
    double x[3];
    pd->GetPoint(i, x);
    s.points[static_cast<size_t>(i)] = length_factor * Vec3(x[0], x[1], x[2]);
    if (!s.points[static_cast<size_t>(i)].allFinite())
      throw_input_error(fmt::format("{}: point {}", path, i), "has a coordinate that is not a finite number");
  }
  vtkCellArray* polys = pd->GetPolys();
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  for (polys->InitTraversal(); polys->GetNextCell(n, ids);) {
    if (n != 3) continue;
    const std::array<int, 3> t{static_cast<int>(ids[0]), static_cast<int>(ids[1]), static_cast<int>(ids[2])};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;  // collapsed by the point merge
    s.triangles.push_back(t);
  }
#else
  throw_input_error(path, "reading a lumen surface needs flowire built with VTK (FLOWIRE_WITH_VTK)");
#endif
  if (s.triangles.empty()) throw_input_error(path, "the surface has no triangles");
  return s;
}

LumenSurface prepare_lumen(const Network& net, SurfaceMesh s, const LumenOptions& opt) {
  const std::vector<int> ends = net.ends();
  if (ends.size() < 2)
    throw_input_error(net.source().empty() ? std::string("centerlines") : net.source(),
                      "the network needs an inlet and at least one outlet end");
  std::vector<std::vector<int>> loops = boundary_loops(s);
  bool was_capped = false;
  int recut = 0;
  if (loops.empty()) {
    clip_ends(s, net, opt.clip_back);
    was_capped = true;
    loops = boundary_loops(s);
  }
  if (loops.size() != ends.size())
    throw_input_error(s.source, fmt::format("the surface has {} open ends but the centerlines {} have {} ends; they "
                                            "must be the same anatomy, one open end per vessel end",
                                            loops.size(), net.source(), ends.size()));
  // An end cut so obliquely that its cap would nearly continue the wall is cut again square to
  // the vessel (mesh_lumen tells caps from the wall by a 40° crease).
  if (!was_capped && (recut = recut_oblique_ends(s, net, loops, kRimAngle)) > 0) {
    loops = boundary_loops(s);
    if (loops.size() != ends.size())
      throw_input_error(s.source,
                        fmt::format("cutting its oblique open ends square left {} open ends for {} centerline ends",
                                    loops.size(), ends.size()));
  }
  // Drop the points no triangle uses, then append the fan centres.
  std::vector<int> renum(s.points.size(), -1);
  SurfaceMesh out;
  out.source = s.source;
  for (auto& t : s.triangles)
    for (int& v : t) {
      int& r = renum[static_cast<size_t>(v)];
      if (r < 0) {
        r = static_cast<int>(out.points.size());
        out.points.push_back(s.points[static_cast<size_t>(v)]);
      }
      v = r;
    }
  out.triangles = std::move(s.triangles);
  for (auto& l : loops)
    for (int& v : l) v = renum[static_cast<size_t>(v)];

  LumenSurface lumen;
  lumen.recut_ends = recut;
  lumen.wall_triangles = static_cast<int>(out.triangles.size());
  struct Cap {
    LumenCap info;
    std::vector<int> loop;
  };
  std::vector<Cap> caps;
  for (const auto& loop : loops) {
    Cap c;
    c.loop = loop;
    double len = 0.0;
    Vec3 centroid = Vec3::Zero();
    const size_t n = loop.size();
    for (size_t i = 0; i < n; ++i) {
      const Vec3& a = out.points[static_cast<size_t>(loop[i])];
      const Vec3& b = out.points[static_cast<size_t>(loop[(i + 1) % n])];
      const double l = (b - a).norm();
      centroid += 0.5 * l * (a + b);
      len += l;
    }
    centroid /= len;
    // Fan triangles (centre, b, a): the opposite of the wall's boundary edge a -> b.
    Vec3 area = Vec3::Zero();
    for (size_t i = 0; i < n; ++i) {
      const Vec3& a = out.points[static_cast<size_t>(loop[i])];
      const Vec3& b = out.points[static_cast<size_t>(loop[(i + 1) % n])];
      area += 0.5 * (b - centroid).cross(a - centroid);
    }
    c.info.centroid = centroid;
    c.info.radius = std::sqrt(area.norm() / std::numbers::pi);
    c.info.normal = area.normalized();
    double dev = 0.0;
    for (int v : loop)
      dev = std::max(dev, std::abs((out.points[static_cast<size_t>(v)] - centroid).dot(c.info.normal)));
    c.info.planarity = dev / c.info.radius;
    c.info.loop_points = static_cast<int>(n);
    c.info.was_capped = was_capped;
    caps.push_back(std::move(c));
  }
  // Match caps and ends one to one, closest pairs first.
  struct Pair {
    double d;
    size_t cap, end;
  };
  std::vector<Pair> pairs;
  for (size_t c = 0; c < caps.size(); ++c)
    for (size_t e = 0; e < ends.size(); ++e)
      pairs.push_back({(caps[c].info.centroid - net.node(ends[e])).norm(), c, e});
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
  std::vector<int> cap_of_end(ends.size(), -1), end_of_cap(caps.size(), -1);
  for (const Pair& p : pairs) {
    if (cap_of_end[p.end] >= 0 || end_of_cap[p.cap] >= 0) continue;
    cap_of_end[p.end] = static_cast<int>(p.cap);
    end_of_cap[p.cap] = static_cast<int>(p.end);
  }
  for (size_t c = 0; c < caps.size(); ++c) {
    const int e = ends[static_cast<size_t>(end_of_cap[c])];
    LumenCap& info = caps[c].info;
    info.node = e;
    info.distance = (info.centroid - net.node(e)).norm();
    const double reach = opt.match_factor * std::max(end_radius(net, e), info.radius);
    // The nearest end of this cap must be its match (else two caps compete for one end).
    size_t nearest = 0;
    for (size_t k = 1; k < ends.size(); ++k)
      if ((info.centroid - net.node(ends[k])).norm() < (info.centroid - net.node(ends[nearest])).norm()) nearest = k;
    if (info.distance > reach || ends[nearest] != e)
      throw_input_error(fmt::format("{}: open end at {}", s.source, mm(info.centroid)),
                        fmt::format("matches no centerline end of {}: the nearest, node {} at {}, is {:.2f} mm away "
                                    "(allowed {:.2f} mm){}; check that the surface and the centerlines are the same "
                                    "anatomy in the same unit",
                                    net.source(), ends[nearest], mm(net.node(ends[nearest])),
                                    1e3 * (info.centroid - net.node(ends[nearest])).norm(), 1e3 * reach,
                                    ends[nearest] != e ? ", and it is nearer to another open end" : ""));
  }
  // Caps in the order of the network ends; the fans appended after the wall.
  for (size_t e = 0; e < ends.size(); ++e) {
    const Cap& c = caps[static_cast<size_t>(cap_of_end[e])];
    const int centre = static_cast<int>(out.points.size());
    out.points.push_back(c.info.centroid);
    const size_t n = c.loop.size();
    for (size_t i = 0; i < n; ++i) out.triangles.push_back({centre, c.loop[(i + 1) % n], c.loop[i]});
    lumen.caps.push_back(c.info);
    lumen.cap_centre.push_back(centre);
  }
  lumen.surface = std::move(out);
  const double v = signed_volume(lumen.surface);
  if (v < 0.0)  // the file's triangles face inwards: so do the fans, and their normals
    for (auto& c : lumen.caps) c.normal = -c.normal;
  lumen.enclosed_volume = std::abs(v);
  return lumen;
}

namespace {

TetMesh mesh_lumen(const Network& net, const LumenSurface& lumen, const MeshOptions& opt) {
  const auto start = std::chrono::steady_clock::now();
  const std::string& at = lumen.surface.source;
  const std::vector<int> ends = net.ends();
  const int inlet = opt.inlet_node >= 0 ? opt.inlet_node : net.widest_end();
  if (std::find(ends.begin(), ends.end(), inlet) == ends.end())
    throw_input_error(at, fmt::format("inlet node {} is not an end of the centerlines {}", inlet, net.source()));
  if (lumen.caps.size() != ends.size())
    throw_input_error(at, fmt::format("{} caps for {} centerline ends", lumen.caps.size(), ends.size()));
  TetMesh mesh;
  mesh.groups.push_back({BoundaryGroup::Kind::Wall, -1, "wall"});
  mesh.groups.push_back({BoundaryGroup::Kind::Inlet, inlet, "inlet"});
  for (int e : ends)
    if (e != inlet) mesh.groups.push_back({BoundaryGroup::Kind::Outlet, e, fmt::format("outlet_{}", e)});

  mesh::GmshModel model(opt.verbose);
  const SurfaceMesh& s = lumen.surface;
  gmsh::model::addDiscreteEntity(2, 1);
  std::vector<std::size_t> node_tags(s.points.size());
  std::iota(node_tags.begin(), node_tags.end(), std::size_t{1});
  std::vector<double> coords;
  coords.reserve(3 * s.points.size());
  for (const Vec3& x : s.points) coords.insert(coords.end(), {x.x(), x.y(), x.z()});
  gmsh::model::mesh::addNodes(2, 1, node_tags, coords);
  std::vector<std::size_t> tri_tags(s.triangles.size()), tri_nodes;
  std::iota(tri_tags.begin(), tri_tags.end(), std::size_t{1});
  tri_nodes.reserve(3 * s.triangles.size());
  for (const auto& t : s.triangles)
    for (int v : t) tri_nodes.push_back(static_cast<std::size_t>(v) + 1);
  gmsh::model::mesh::addElementsByType(1, 2, tri_tags, tri_nodes);
  // Patches split at sharp edges (the cap rims), each one parametrizable.
  gmsh::model::mesh::classifySurfaces(kCreaseAngle, true, true, std::numbers::pi);
  gmsh::model::mesh::createGeometry();

  gmsh::vectorpair surfs;
  gmsh::model::getEntities(surfs, 2);
  std::unordered_map<std::size_t, int> cap_of_centre;  // gmsh node tag of a fan centre -> cap
  for (size_t c = 0; c < lumen.cap_centre.size(); ++c)
    cap_of_centre[static_cast<std::size_t>(lumen.cap_centre[c]) + 1] = static_cast<int>(c);
  std::vector<int> surf_group(surfs.size(), 0);
  std::vector<int> cap_triangles(lumen.caps.size(), 0);
  for (size_t k = 0; k < surfs.size(); ++k) {
    std::vector<std::size_t> etags, enodes;
    gmsh::model::mesh::getElementsByType(2, etags, enodes, surfs[k].second);
    int cap = -1, with = 0;
    for (size_t e = 0; e < etags.size(); ++e)
      for (int j = 0; j < 3; ++j)
        if (auto it = cap_of_centre.find(enodes[3 * e + static_cast<size_t>(j)]); it != cap_of_centre.end()) {
          cap = it->second;
          ++with;
        }
    if (cap < 0) continue;
    const LumenCap& info = lumen.caps[static_cast<size_t>(cap)];
    if (with != static_cast<int>(etags.size()))
      throw_input_error(fmt::format("{}: open end at {}", at, mm(info.centroid)),
                        "the cap could not be told from the wall (the wall meets it at less than 40 degrees)");
    cap_triangles[static_cast<size_t>(cap)] += with;
    surf_group[k] = mesh.group_of_node(info.node);
  }
  for (size_t c = 0; c < lumen.caps.size(); ++c)
    if (cap_triangles[c] != lumen.caps[c].loop_points)
      throw_input_error(fmt::format("{}: open end at {}", at, mm(lumen.caps[c].centroid)),
                        "the cap could not be told from the wall (the wall meets it at less than 40 degrees)");
  std::vector<int> tags;
  for (const auto& sf : surfs) tags.push_back(sf.second);
  const int loop = gmsh::model::geo::addSurfaceLoop(tags);
  gmsh::model::geo::addVolume({loop});
  gmsh::model::geo::synchronize();
  gmsh::vectorpair vols;
  gmsh::model::getEntities(vols, 3);
  if (vols.size() != 1) throw_numerical_error(fmt::format("{}: the lumen gave {} volumes, not one", at, vols.size()));
  mesh::tag_groups_and_set_options(vols[0].second, "lumen", mesh.groups, surfs, surf_group, opt.algorithm3d);

  if (!mesh::set_size_bounds(opt.mesh_size, opt.size_factor)) {
    struct Axis {
      Vec3 a, d;
      double l2, r;
    };
    std::vector<Axis> axes;
    for (int k = 0; k < net.num_segments(); ++k) {
      const auto& seg = net.segment(k);
      const Vec3 a = net.node(seg.node_from), d = net.node(seg.node_to) - a;
      axes.push_back({a, d, d.squaredNorm(), seg.radius});
    }
    const double factor = opt.size_factor;
    gmsh::model::mesh::setSizeCallback([axes = std::move(axes), factor](int, int, double x, double y, double z) {
      const Vec3 p(x, y, z);
      double best = std::numeric_limits<double>::infinity(), r = axes.front().r;
      for (const Axis& ax : axes) {
        const double t = ax.l2 > 0.0 ? std::clamp((p - ax.a).dot(ax.d) / ax.l2, 0.0, 1.0) : 0.0;
        const double dist = (p - ax.a - t * ax.d).norm() - ax.r;
        if (dist < best) {
          best = dist;
          r = ax.r;
        }
      }
      return factor * r;
    });
  }
  mesh::generate(opt);
  mesh::extract_mesh(mesh, surfs, surf_group, at);
  mesh::repair_edge_nodes(mesh);
  mesh.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return mesh;
}

}  // namespace

TetMesh build_mesh(const Network& net, const LumenSurface& lumen, const MeshOptions& opt) {
  return detail::build_shared(
      [&] { return mesh::guarded(lumen.surface.source, [&] { return mesh_lumen(net, lumen, opt); }); });
}

}  // namespace flowire::flow::fem
