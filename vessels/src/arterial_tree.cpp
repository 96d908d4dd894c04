// The 33-artery network of Alastruey et al. 2007 with the circle of Willis.
//
// Source of the numbers: J. Alastruey, K.H. Parker, J. Peiró, S.M. Byrd, S.J. Sherwin,
// "Modelling the circle of Willis to assess the effects of anatomical variations and
// occlusions on cerebral flows", J. Biomech. 40 (2007) 1794–1805, Table 1: per vessel the
// length l (cm), lumen radius r0 (mm), wall thickness h (mm), Young's modulus E (MPa) and,
// for the 11 terminal vessels, the peripheral resistance R (10⁹ Pa·s/m³) and compliance
// C (10⁻¹⁰ m³/Pa). The same table, with the paper's junction numbering, is distributed as the
// openBF model models/alastruey2007/circle_of_willis.yaml (github.com/INSIGNEO/openBF,
// commit 0376f4dc266ff0eec83cb1982f38a6f5b64ad2dc). The table below keeps the published
// units; they are converted to SI (m, Pa, Pa·s/m³, m³/Pa) when read.
//
// The paper gives one radius per vessel (no taper), so proximal and distal radii are equal;
// the table keeps both so that tapered variants can be entered as published.
//
// The paper gives no 3D geometry. The layout here is schematic but anatomically oriented
// (+x: patient's left, +y: anterior, +z: cranial; aortic root at the origin): the aorta rises,
// arches posteriorly to the left and descends along −z; the subclavian and brachial arteries
// run sideways along ±x; carotids and vertebrals rise along +z to the circle of Willis, a
// closed ring about 0.22 m above the aortic root. Every branch has exactly its published arc
// length. Branches whose two ends are both fixed by the rest of the network (the carotids,
// vertebrals and the anterior communicating artery: the vessels that close the loops) are
// longer than the distance between their ends, so they are drawn off the chord as
// h·sin(kπt) (a single bow, k = 1, or for the carotids a tortuous k = 3), with h solved so
// that the polyline length equals the published length. Network::build cuts these curved
// branches into straight segments, so the network's total length is slightly (≈0.2%) below
// the published total; the centerlines themselves carry the exact lengths.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/vessels/arterial_tree.hpp"
#include "flowire/vessels/generators.hpp"

namespace flowire::vessels {
namespace {

constexpr double kCm = 1e-2;  // m
constexpr double kMm = 1e-3;  // m

/// One row of Table 1 (published units). Nodes use the paper's / openBF's numbering.
struct Row {
  int id;
  const char* name;
  int sn, tn;       // proximal, distal node
  double l_cm;      // length
  double r_in_mm;   // proximal radius
  double r_out_mm;  // distal radius
  double h_mm;      // wall thickness
  double e_mpa;     // Young's modulus
};

// clang-format off
constexpr std::array<Row, 33> kRows{{
  { 1, "ascending_aorta",              1,  2,  4.0, 12.0,  12.0,  1.63, 0.4},
  { 2, "aortic_arch_1",                2,  3,  2.0, 11.2,  11.2,  1.26, 0.4},
  { 3, "brachiocephalic",              2,  4,  3.4,  6.2,   6.2,  0.80, 0.4},
  { 4, "aortic_arch_2",                3,  5,  3.9, 10.7,  10.7,  1.15, 0.4},
  { 5, "left_common_carotid",          3,  6, 20.8,  2.5,   2.5,  0.63, 0.4},
  { 6, "right_common_carotid",         4,  7, 17.7,  2.5,   2.5,  0.63, 0.4},
  { 7, "right_subclavian",             4,  8,  3.4,  4.23,  4.23, 0.67, 0.4},
  { 8, "thoracic_aorta",               5,  9, 15.6,  9.99,  9.99, 1.10, 0.4},
  { 9, "left_subclavian",              5, 10,  3.4,  4.23,  4.23, 0.67, 0.4},
  {10, "left_external_carotid",        6, 11, 17.7,  1.5,   1.5,  0.38, 0.8},
  {11, "left_internal_carotid_1",      6, 12, 17.7,  2.0,   2.0,  0.50, 0.8},
  {12, "right_internal_carotid_1",     7, 13, 17.7,  2.0,   2.0,  0.50, 0.8},
  {13, "right_external_carotid",       7, 14, 17.7,  1.5,   1.5,  0.38, 0.8},
  {14, "right_vertebral",              8, 15, 14.8,  1.36,  1.36, 0.34, 0.8},
  {15, "right_brachial",               8, 16, 42.2,  4.03,  4.03, 0.67, 0.4},
  {16, "left_brachial",               10, 17, 42.2,  4.03,  4.03, 0.67, 0.4},
  {17, "left_vertebral",              10, 15, 14.8,  1.36,  1.36, 0.34, 0.8},
  {18, "left_internal_carotid_2",     12, 18,  0.5,  2.0,   2.0,  0.50, 1.6},
  {19, "left_posterior_communicating", 19, 12,  1.5,  0.73,  0.73, 0.18, 1.6},
  {20, "right_posterior_communicating", 20, 13, 1.5,  0.73,  0.73, 0.18, 1.6},
  {21, "right_internal_carotid_2",    13, 21,  0.5,  2.0,   2.0,  0.50, 1.6},
  {22, "basilar",                     15, 22,  2.9,  1.62,  1.62, 0.40, 1.6},
  {23, "left_middle_cerebral",        18, 23, 11.9,  1.43,  1.43, 0.36, 1.6},
  {24, "right_middle_cerebral",       21, 24, 11.9,  1.43,  1.43, 0.36, 1.6},
  {25, "left_anterior_cerebral_a1",   18, 25,  1.2,  1.17,  1.17, 0.29, 1.6},
  {26, "right_anterior_cerebral_a1",  21, 26,  1.2,  1.17,  1.17, 0.29, 1.6},
  {27, "left_posterior_cerebral_p1",  22, 19,  0.5,  1.07,  1.07, 0.27, 1.6},
  {28, "right_posterior_cerebral_p1", 22, 20,  0.5,  1.07,  1.07, 0.27, 1.6},
  {29, "left_anterior_cerebral_a2",   25, 27, 10.3,  1.2,   1.2,  0.30, 1.6},
  {30, "right_anterior_cerebral_a2",  26, 28, 10.3,  1.2,   1.2,  0.30, 1.6},
  {31, "anterior_communicating",      25, 26,  0.3,  0.74,  0.74, 0.19, 1.6},
  {32, "left_posterior_cerebral_p2",  19, 29,  8.6,  1.05,  1.05, 0.26, 1.6},
  {33, "right_posterior_cerebral_p2", 20, 30,  8.6,  1.05,  1.05, 0.26, 1.6},
}};
// clang-format on

/// Terminal vessels: peripheral resistance R (10⁹ Pa·s/m³) and compliance C (10⁻¹⁰ m³/Pa).
struct TerminalRow {
  int id;
  double r_1e9;
  double c_1e_10;
};
constexpr std::array<TerminalRow, 11> kTerminals{{
    {8, 0.18, 38.7},    // thoracic aorta
    {10, 5.43, 1.27},   // left external carotid
    {13, 5.43, 1.27},   // right external carotid
    {15, 2.68, 2.58},   // right brachial
    {16, 2.68, 2.58},   // left brachial
    {23, 5.97, 1.16},   // left middle cerebral
    {24, 5.97, 1.16},   // right middle cerebral
    {29, 8.48, 0.82},   // left anterior cerebral A2
    {30, 8.48, 0.82},   // right anterior cerebral A2
    {32, 11.08, 0.62},  // left posterior cerebral P2
    {33, 11.08, 0.62},  // right posterior cerebral P2
}};

constexpr int kNodes = 30;  // nodes 1..30

const Row& row(int id) { return kRows[static_cast<size_t>(id - 1)]; }

Vec3 ahead(const Vec3& from, double length, const Vec3& dir) { return from + length * dir.normalized(); }
Vec3 mirror_x(const Vec3& v) { return {-v.x(), v.y(), v.z()}; }

/// Positions (cm) of the junction nodes and, per vessel, a direction: the heading of a
/// terminal vessel, or the side a loop vessel bows out to.
struct Layout {
  std::array<Vec3, kNodes + 1> node;  // index 0 unused
  std::array<Vec3, 33> dir;           // by vessel id - 1
  std::array<int, 33> half_waves;     // bow shape of loop vessels: sin(kπt)
};

Layout layout() {
  Layout g;
  auto& n = g.node;
  for (auto& v : n) v = Vec3::Constant(std::nan(""));
  for (auto& v : g.dir) v = Vec3::Zero();
  g.half_waves.fill(1);
  auto dir = [&](int id, const Vec3& d) { g.dir[static_cast<size_t>(id - 1)] = d; };
  // Aorta: up from the root, arch to the left and back, thoracic aorta down.
  n[1] = Vec3::Zero();
  n[2] = ahead(n[1], row(1).l_cm, Vec3(-0.10, 0.15, 1.0));
  n[3] = ahead(n[2], row(2).l_cm, Vec3(0.80, -0.50, 0.30));
  n[4] = ahead(n[2], row(3).l_cm, Vec3(-0.45, 0.10, 1.0));
  n[5] = ahead(n[3], row(4).l_cm, Vec3(0.30, -1.0, -0.55));
  dir(8, Vec3(0.0, 0.05, -1.0));
  // Subclavians sideways and up; brachials along ±x, down the arms.
  n[8] = ahead(n[4], row(7).l_cm, Vec3(-1.0, -0.10, 0.25));
  n[10] = ahead(n[5], row(9).l_cm, Vec3(0.50, 0.40, 1.0));
  dir(15, Vec3(-1.0, 0.05, -0.25));
  dir(16, Vec3(1.0, 0.05, -0.25));
  // Vertebrals meet on the midline, behind, where the basilar artery starts.
  n[15] = Vec3(0.0, -2.0, 19.6);
  dir(14, Vec3(-1.0, -0.3, 0.0));
  dir(17, Vec3(1.0, -0.3, 0.0));
  // Circle of Willis, symmetric about x = 0: basilar tip, P1 to the PCA junctions, PCoA
  // forward to the internal carotid, ICA II up to its terminus, A1 forward and inward.
  n[22] = ahead(n[15], row(22).l_cm, Vec3(0.0, 0.35, 1.0));
  n[19] = ahead(n[22], row(27).l_cm, Vec3(1.0, 0.0, 0.15));
  n[12] = ahead(n[19], row(19).l_cm, Vec3(0.25, 1.0, 0.0));
  n[18] = ahead(n[12], row(18).l_cm, Vec3(0.0, 0.5, 1.0));
  n[25] = ahead(n[18], row(25).l_cm, Vec3(-0.80, 1.0, 0.10));
  n[20] = mirror_x(n[19]);
  n[13] = mirror_x(n[12]);
  n[21] = mirror_x(n[18]);
  n[26] = mirror_x(n[25]);
  dir(31, Vec3(0.0, 1.0, 0.2));  // ACoA bows forward
  dir(23, Vec3(1.0, 0.0, 0.8));  // MCA: lateral and up
  dir(24, Vec3(-1.0, 0.0, 0.8));
  dir(29, Vec3(0.05, 1.0, 1.1));  // ACA A2: forward and up
  dir(30, Vec3(-0.05, 1.0, 1.1));
  dir(32, Vec3(0.5, -1.0, 0.3));  // PCA P2: backward
  dir(33, Vec3(-0.5, -1.0, 0.3));
  // Carotid bifurcations in the neck. The published carotid path (common + internal, 35–38 cm)
  // is about twice the distance from the arch to the circle, so these vessels are drawn
  // tortuous: three half-waves, mainly in the sagittal plane.
  n[6] = Vec3(4.5, 2.0, 14.0);
  n[7] = mirror_x(n[6]);
  for (int id : {5, 6, 11, 12}) g.half_waves[static_cast<size_t>(id - 1)] = 3;
  dir(5, Vec3(0.35, 1.0, 0.0));
  dir(6, Vec3(-0.35, 1.0, 0.0));
  dir(11, Vec3(0.35, 1.0, 0.0));
  dir(12, Vec3(-0.35, 1.0, 0.0));
  dir(10, Vec3(0.3, 0.6, 1.0));  // external carotids: forward and up (face)
  dir(13, Vec3(-0.3, 0.6, 1.0));
  // Terminal nodes: straight along the vessel's heading.
  for (const Row& r : kRows)
    if (!n[static_cast<size_t>(r.tn)].allFinite())
      n[static_cast<size_t>(r.tn)] = ahead(n[static_cast<size_t>(r.sn)], r.l_cm, g.dir[static_cast<size_t>(r.id - 1)]);
  return g;
}

double polyline_length(const std::vector<Vec3>& p) {
  double s = 0.0;
  for (size_t i = 1; i < p.size(); ++i) s += (p[i] - p[i - 1]).norm();
  return s;
}

/// Centerline points from a to b with arc length `length`: straight when |b − a| equals
/// it, otherwise a bow a + t(b − a) + h·sin(kπt)·side (k half-waves) with h found by bisection.
std::vector<Vec3> connect(const Vec3& a, const Vec3& b, double length, const Vec3& side_hint, int half_waves,
                          const char* name) {
  const Vec3 chord = b - a;
  const double d = chord.norm();
  if (d > length * (1.0 + 1e-9))
    throw_numerical_error(fmt::format("arterial_tree: {} cannot span its end points ({} > {} cm)", name, d, length));
  if (d >= length * (1.0 - 1e-12)) {
    std::vector<Vec3> p;
    constexpr int pieces = 3;
    for (int i = 0; i <= pieces; ++i) p.push_back(a + (static_cast<double>(i) / pieces) * chord);
    p.back() = b;
    return p;
  }
  const Vec3 e = chord / d;
  Vec3 side = side_hint - side_hint.dot(e) * e;
  if (!(side.norm() > 1e-6)) side = e.cross(std::abs(e.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY());
  side.normalize();
  // One point per 2.5 mm of length, at least 16 pieces.
  const int pieces = std::max(16, static_cast<int>(std::ceil(length / 0.25)));
  auto shape = [&](double h) {
    std::vector<Vec3> p;
    p.reserve(static_cast<size_t>(pieces) + 1);
    for (int i = 0; i <= pieces; ++i) {
      const double t = static_cast<double>(i) / pieces;
      p.push_back(a + t * chord + (h * std::sin(std::numbers::pi * half_waves * t)) * side);
    }
    p.front() = a;
    p.back() = b;
    return p;
  };
  // The length grows monotonically with h; bracket, then bisect to round-off.
  double lo = 0.0, hi = length;
  while (polyline_length(shape(hi)) < length) hi *= 2.0;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * length; ++it) {
    const double mid = 0.5 * (lo + hi);
    (polyline_length(shape(mid)) < length ? lo : hi) = mid;
  }
  return shape(0.5 * (lo + hi));
}

}  // namespace

std::vector<ArterialTreeVessel> arterial_tree_vessels() {
  std::vector<ArterialTreeVessel> v;
  v.reserve(kRows.size());
  for (const Row& r : kRows)
    v.push_back(
        {r.id, r.name, r.sn, r.tn, r.l_cm * kCm, r.r_in_mm * kMm, r.r_out_mm * kMm, r.h_mm * kMm, r.e_mpa * 1e6});
  return v;
}

std::vector<std::pair<std::string, double>> arterial_tree_terminal_resistances() {
  std::vector<std::pair<std::string, double>> out;
  for (const TerminalRow& t : kTerminals) out.emplace_back(row(t.id).name, t.r_1e9 * 1e9);
  return out;
}

std::vector<std::pair<std::string, double>> arterial_tree_terminal_compliances() {
  std::vector<std::pair<std::string, double>> out;
  for (const TerminalRow& t : kTerminals) out.emplace_back(row(t.id).name, t.c_1e_10 * 1e-10);
  return out;
}

Centerlines arterial_tree(const ArterialTreeParams& p) {
  if (!(p.scale > 0.0) || !std::isfinite(p.scale))
    throw_usage_error(fmt::format("generator parameter 'scale' must be positive and finite (got {})", p.scale));
  const Layout g = layout();
  const double to_m = kCm * p.scale;
  Centerlines c;
  c.source = "arterial_tree";
  c.branches.reserve(kRows.size());
  for (const Row& r : kRows) {
    const auto pts = connect(g.node[static_cast<size_t>(r.sn)], g.node[static_cast<size_t>(r.tn)], r.l_cm,
                             g.dir[static_cast<size_t>(r.id - 1)], g.half_waves[static_cast<size_t>(r.id - 1)], r.name);
    Polyline poly;
    poly.name = r.name;
    poly.points.reserve(pts.size());
    poly.radii.reserve(pts.size());
    // Radius linear in arc length between the published proximal and distal radii.
    double s = 0.0;
    const double total = polyline_length(pts);
    for (size_t i = 0; i < pts.size(); ++i) {
      if (i > 0) s += (pts[i] - pts[i - 1]).norm();
      const double w = i + 1 == pts.size() ? 1.0 : s / total;
      poly.points.push_back(to_m * pts[i]);
      poly.radii.push_back(kMm * p.scale * ((1.0 - w) * r.r_in_mm + w * r.r_out_mm));
    }
    c.branches.push_back(std::move(poly));
  }
  return c;
}

}  // namespace flowire::vessels
