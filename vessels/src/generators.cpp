#include "flowire/vessels/generators.hpp"

#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "flowire/common/error.hpp"

namespace flowire::vessels {
namespace {

constexpr double kPi = std::numbers::pi;

void require_positive(double v, const char* name) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw_usage_error(fmt::format("generator parameter '{}' must be positive and finite (got {})", name, v));
}

Polyline straight(std::string name, const Vec3& a, const Vec3& b, double ra, double rb, int pieces = 1) {
  Polyline p;
  p.name = std::move(name);
  for (int i = 0; i <= pieces; ++i) {
    const double w = static_cast<double>(i) / pieces;
    p.points.push_back((1.0 - w) * a + w * b);
    p.radii.push_back((1.0 - w) * ra + w * rb);
  }
  return p;
}

/// Any unit vector perpendicular to d.
Vec3 perpendicular(const Vec3& d) {
  const Vec3 t = std::abs(d.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return d.cross(t).normalized();
}

}  // namespace

Centerlines straight_tube(const StraightTubeParams& p) {
  require_positive(p.length, "length");
  require_positive(p.radius, "radius");
  if (!(p.direction.norm() > 0.0)) throw_usage_error("straight_tube: direction must be non-zero");
  Centerlines c;
  c.source = "straight_tube";
  const Vec3 d = p.direction.normalized();
  c.branches.push_back(straight("tube", p.origin, p.origin + p.length * d, p.radius, p.radius));
  return c;
}

Centerlines y_bifurcation(const YBifurcationParams& p) {
  require_positive(p.parent_radius, "parent_radius");
  require_positive(p.parent_length, "parent_length");
  require_positive(p.child_length, "child_length");
  if (!(p.asymmetry > -1.0 && p.asymmetry < 1.0)) throw_usage_error("y_bifurcation: asymmetry must be in (-1, 1)");
  if (!(p.angle > 0.0 && p.angle < kPi / 2)) throw_usage_error("y_bifurcation: angle must be in (0, pi/2)");
  const double r3 = std::pow(p.parent_radius, 3);
  const double r1 = std::cbrt(0.5 * (1.0 + p.asymmetry) * r3);
  const double r2 = std::cbrt(0.5 * (1.0 - p.asymmetry) * r3);
  const Vec3 j(p.parent_length, 0, 0);
  const Vec3 d1(std::cos(p.angle), std::sin(p.angle), 0);
  const Vec3 d2(std::cos(p.angle), -std::sin(p.angle), 0);
  Centerlines c;
  c.source = "y_bifurcation";
  c.branches.push_back(straight("parent", Vec3::Zero(), j, p.parent_radius, p.parent_radius));
  c.branches.push_back(straight("daughter_1", j, j + p.child_length * d1, r1, r1));
  c.branches.push_back(straight("daughter_2", j, j + p.child_length * d2, r2, r2));
  return c;
}

namespace {

/// The aortic centreline and its branch points, lengths in m before scaling.
struct Arch {
  double s;
  int ppcm;
  // Arch: half circle in the y–z plane from the top of the ascending aorta, drifting to
  // the patient's left (+x) so the descending aorta lies left of the midline.
  static constexpr double h_asc = 0.05;    // ascending aorta height
  static constexpr double R_arch = 0.028;  // arch radius of curvature
  [[nodiscard]] Vec3 arch(double theta) const {
    return s * Vec3(0.025 * theta / kPi, -R_arch + R_arch * std::cos(theta), h_asc + R_arch * std::sin(theta));
  }
  [[nodiscard]] double arch_radius(double theta) const { return s * (0.0140 - 0.0025 * theta / kPi); }
  // Descending + abdominal aorta: from the arch end (theta = pi) down to the iliac bifurcation.
  [[nodiscard]] Vec3 descending(double u) const {  // u in [0, 1]
    const Vec3 a = arch(kPi) / s;
    const double z = a.z() - 0.40 * u;
    const double y = a.y() + 0.030 * std::sin(kPi * u * 0.5) * u;  // abdominal aorta moves anterior
    const double x = a.x() * (1.0 - 0.6 * u);
    return s * Vec3(x, y, z);
  }
  [[nodiscard]] double descending_radius(double u) const { return s * (0.0115 - 0.0030 * u); }
  [[nodiscard]] int pieces(double length) const {
    return std::max(2, static_cast<int>(std::ceil(length * 100 * ppcm)));
  }
};

Polyline sample(std::string name, int n, const std::function<Vec3(double)>& pos,
                const std::function<double(double)>& rad) {
  Polyline p;
  p.name = std::move(name);
  for (int i = 0; i <= n; ++i) {
    const double u = static_cast<double>(i) / n;
    p.points.push_back(pos(u));
    p.radii.push_back(rad(u));
  }
  return p;
}

Polyline iliac_femoral(const Arch& a, const Vec3& bif, double side, std::string name) {
  // Common iliac (6 cm, 5 mm) out and down, then external iliac / femoral (12 cm, 4 mm) down.
  const Vec3 d1 = Vec3(side * 0.45, 0.12, -0.88).normalized();
  const Vec3 knee = bif + a.s * 0.06 * d1;
  const Vec3 d2 = Vec3(side * 0.12, 0.15, -0.98).normalized();
  const Vec3 end = knee + a.s * 0.12 * d2;
  const int n1 = a.pieces(0.06), n2 = a.pieces(0.12);
  Polyline p;
  p.name = std::move(name);
  for (int i = 0; i <= n1; ++i) {
    const double u = static_cast<double>(i) / n1;
    p.points.push_back(bif + u * (knee - bif));
    p.radii.push_back(a.s * (0.0055 - 0.0007 * u));
  }
  for (int i = 1; i <= n2; ++i) {
    const double u = static_cast<double>(i) / n2;
    p.points.push_back(knee + u * (end - knee));
    p.radii.push_back(a.s * (0.0048 - 0.0008 * u));
  }
  return p;
}

}  // namespace

Centerlines aortic_arch(const AorticArchParams& p) {
  require_positive(p.scale, "scale");
  if (p.points_per_cm < 1) throw_usage_error("aortic_arch: points_per_cm must be at least 1");
  const Arch a{p.scale, p.points_per_cm};
  const double th_bca = 0.35 * kPi, th_lcc = 0.50 * kPi, th_lsa = 0.65 * kPi;
  Centerlines c;
  c.source = "aortic_arch";
  // Ascending aorta: straight up from the root, then the first part of the arch.
  {
    Polyline asc;
    asc.name = "ascending_aorta";
    const int n = a.pieces(Arch::h_asc);
    for (int i = 0; i < n; ++i) {
      const double u = static_cast<double>(i) / n;
      asc.points.push_back(p.scale * Vec3(0, 0, Arch::h_asc * u));
      asc.radii.push_back(p.scale * 0.0140);
    }
    const int m = a.pieces(Arch::R_arch * th_bca);
    for (int i = 0; i <= m; ++i) {
      const double th = th_bca * i / m;
      asc.points.push_back(a.arch(th));
      asc.radii.push_back(a.arch_radius(th));
    }
    c.branches.push_back(std::move(asc));
  }
  auto arch_piece = [&](std::string name, double t0, double t1) {
    return sample(
        std::move(name), a.pieces(Arch::R_arch * (t1 - t0)),
        [&, t0, t1](double u) { return a.arch(t0 + u * (t1 - t0)); },
        [&, t0, t1](double u) { return a.arch_radius(t0 + u * (t1 - t0)); });
  };
  c.branches.push_back(arch_piece("arch_1", th_bca, th_lcc));
  c.branches.push_back(arch_piece("arch_2", th_lcc, th_lsa));
  {
    Polyline desc = arch_piece("descending_aorta", th_lsa, kPi);
    const int n = a.pieces(0.40);
    for (int i = 1; i <= n; ++i) {
      const double u = static_cast<double>(i) / n;
      desc.points.push_back(a.descending(u));
      desc.radii.push_back(a.descending_radius(u));
    }
    c.branches.push_back(std::move(desc));
  }
  auto side_branch = [&](std::string name, double th, const Vec3& dir, double len, double r0, double r1) {
    const Vec3 o = a.arch(th);
    const Vec3 d = dir.normalized();
    return straight(std::move(name), o, o + p.scale * len * d, p.scale * r0, p.scale * r1, a.pieces(len));
  };
  c.branches.push_back(side_branch("brachiocephalic", th_bca, Vec3(-0.45, 0.15, 1.0), 0.045, 0.0065, 0.0060));
  c.branches.push_back(side_branch("left_common_carotid", th_lcc, Vec3(0.10, 0.10, 1.0), 0.10, 0.0042, 0.0038));
  c.branches.push_back(side_branch("left_subclavian", th_lsa, Vec3(0.75, 0.0, 0.65), 0.07, 0.0052, 0.0045));
  const Vec3 bif = a.descending(1.0);
  c.branches.push_back(iliac_femoral(a, bif, -1.0, "right_iliac_femoral"));
  c.branches.push_back(iliac_femoral(a, bif, +1.0, "left_iliac_femoral"));
  return c;
}

Vec3 aortic_arch_entry(const AorticArchParams& p) {
  const auto c = aortic_arch(p);
  for (const auto& b : c.branches)
    if (b.name == "right_iliac_femoral") return b.points.back();
  return Vec3::Zero();
}

Network binary_tree(const BinaryTreeParams& p) {
  require_positive(p.root_radius, "root_radius");
  require_positive(p.root_length, "root_length");
  require_positive(p.radius_ratio, "radius_ratio");
  require_positive(p.length_ratio, "length_ratio");
  if (p.depth < 0 || p.depth > 24) throw_usage_error("binary_tree: depth must be in 0..24");
  const size_t nv = (size_t{1} << (p.depth + 1)) - 1;
  std::vector<Vec3> nodes(nv + 1);
  std::vector<Segment> segs(nv);
  std::vector<Vec3> dir(nv), side(nv);
  nodes[0] = Vec3::Zero();
  const double ca = std::cos(p.angle), sa = std::sin(p.angle);
  for (size_t v = 0; v < nv; ++v) {
    int gen = 0;
    for (size_t t = v + 1; t > 1; t >>= 1) ++gen;
    const size_t from = v == 0 ? 0 : (v - 1) / 2 + 1;
    if (v == 0) {
      dir[0] = Vec3::UnitX();
      side[0] = Vec3::UnitY();
    } else {
      const size_t par = (v - 1) / 2;
      const double sign = (v % 2 == 1) ? 1.0 : -1.0;
      dir[v] = (ca * dir[par] + sign * sa * side[par]).normalized();
      side[v] = dir[v].cross(side[par]).normalized();  // next branching plane turned by 90°
      if (!side[v].allFinite() || side[v].norm() < 0.5) side[v] = perpendicular(dir[v]);
    }
    const double len = p.root_length * std::pow(p.length_ratio, gen);
    nodes[v + 1] = nodes[from] + len * dir[v];
    segs[v].node_from = static_cast<int>(from);
    segs[v].node_to = static_cast<int>(v + 1);
    segs[v].radius = p.root_radius * std::pow(p.radius_ratio, gen);
    segs[v].length = len;
  }
  return Network::from_graph(std::move(nodes), std::move(segs), {}, "binary_tree");
}

}  // namespace flowire::vessels
