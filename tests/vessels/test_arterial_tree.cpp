// The 33-artery network of Alastruey et al. 2007 (J. Biomech. 40:1794–1805, Table 1).
#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <map>
#include <set>
#include <string>

#include "flowire/common/error.hpp"
#include "flowire/vessels/arterial_tree.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/network.hpp"
#include "flowire_test.hpp"

namespace flowire::vessels {
namespace {

double arc_length(const Polyline& p) {
  double s = 0.0;
  for (size_t i = 1; i < p.points.size(); ++i) s += (p.points[i] - p.points[i - 1]).norm();
  return s;
}

const Polyline& branch(const Centerlines& c, const std::string& name) {
  for (const auto& b : c.branches)
    if (b.name == name) return b;
  throw std::runtime_error("no branch " + name);
}

TEST(ArterialTree, HasThePublishedVessels) {
  const Centerlines c = arterial_tree();
  const auto table = arterial_tree_vessels();
  ASSERT_EQ(c.branches.size(), 33u);
  ASSERT_EQ(table.size(), 33u);
  std::set<std::string> names;
  for (size_t i = 0; i < table.size(); ++i) {
    EXPECT_EQ(table[i].id, static_cast<int>(i) + 1);
    EXPECT_EQ(c.branches[i].name, table[i].name);
    EXPECT_EQ(c.branches[i].points.size(), c.branches[i].radii.size());
    EXPECT_GE(c.branches[i].points.size(), 2u);
    names.insert(table[i].name);
  }
  EXPECT_EQ(names.size(), 33u) << "branch names must be unique";
}

TEST(ArterialTree, LengthsAndRadiiFollowTheTable) {
  const Centerlines c = arterial_tree();
  const auto table = arterial_tree_vessels();
  for (size_t i = 0; i < table.size(); ++i) {
    const auto& v = table[i];
    const auto& b = c.branches[i];
    EXPECT_NEAR(arc_length(b), v.length, 1e-12 * v.length) << v.name;
    EXPECT_NEAR(b.radii.front(), v.radius_in, 1e-15) << v.name;
    EXPECT_NEAR(b.radii.back(), v.radius_out, 1e-15) << v.name;
    for (double r : b.radii) {
      EXPECT_GE(r, std::min(v.radius_in, v.radius_out) - 1e-15) << v.name;
      EXPECT_LE(r, std::max(v.radius_in, v.radius_out) + 1e-15) << v.name;
    }
  }
}

TEST(ArterialTree, NamedVesselsMatchThePaper) {
  // Table 1 of Alastruey et al. 2007: length (cm), radius (mm).
  struct Expect {
    const char* name;
    double l_cm, r_mm;
  };
  const Expect published[] = {
      {"ascending_aorta", 4.0, 12.0},
      {"aortic_arch_2", 3.9, 10.7},
      {"thoracic_aorta", 15.6, 9.99},
      {"left_common_carotid", 20.8, 2.5},
      {"right_common_carotid", 17.7, 2.5},
      {"right_vertebral", 14.8, 1.36},
      {"left_brachial", 42.2, 4.03},
      {"basilar", 2.9, 1.62},
      {"left_posterior_communicating", 1.5, 0.73},
      {"right_middle_cerebral", 11.9, 1.43},
      {"anterior_communicating", 0.3, 0.74},
      {"left_posterior_cerebral_p2", 8.6, 1.05},
  };
  const Centerlines c = arterial_tree();
  for (const auto& e : published) {
    const Polyline& b = branch(c, e.name);
    EXPECT_NEAR(arc_length(b), e.l_cm * 1e-2, 1e-12) << e.name;
    for (double r : b.radii) EXPECT_NEAR(r, e.r_mm * 1e-3, 1e-15) << e.name;
  }
  const auto table = arterial_tree_vessels();
  EXPECT_DOUBLE_EQ(table[0].wall_thickness, 1.63e-3);
  EXPECT_DOUBLE_EQ(table[0].young_modulus, 0.4e6);
  EXPECT_DOUBLE_EQ(table[30].young_modulus, 1.6e6);
}

TEST(ArterialTree, TotalLength) {
  // Sum of the 33 published lengths: 331.2 cm.
  const Centerlines c = arterial_tree();
  double total = 0.0;
  for (const auto& b : c.branches) total += arc_length(b);
  EXPECT_NEAR(total, 3.312, 1e-12);
  // Segments are chords of the curved (loop-closing) branches: a little shorter.
  const auto counts = Network::build(c).counts();
  EXPECT_LE(counts.total_length, 3.312 + 1e-12);
  EXPECT_NEAR(counts.total_length, 3.312, 0.005 * 3.312);
}

TEST(ArterialTree, GraphHasThePublishedLoopsAndEnds) {
  const Network net = Network::build(arterial_tree());
  const auto k = net.counts();
  EXPECT_EQ(k.branches, 33);
  EXPECT_EQ(k.components, 1);
  // 33 vessels between 30 nodes: 33 − 30 + 1 = 4 independent loops (vertebral confluence,
  // the circle of Willis, and the two carotid paths into it).
  EXPECT_EQ(k.loops, 4);
  // The aortic root and the 11 terminal vessels.
  EXPECT_EQ(k.ends, 12);
  EXPECT_EQ(k.junctions, 18);
  EXPECT_NEAR(k.radius_max, 12e-3, 1e-15);
  EXPECT_NEAR(k.radius_min, 0.73e-3, 1e-15);
  // The inlet is the aortic root, at the origin.
  EXPECT_LT(net.node(net.widest_end()).norm(), 1e-15);
}

TEST(ArterialTree, BranchesMeetAtThePublishedJunctions) {
  const Centerlines c = arterial_tree();
  const auto table = arterial_tree_vessels();
  // Every vessel starts exactly where the other vessels at its proximal node start or end.
  std::map<int, Vec3> at;
  for (size_t i = 0; i < table.size(); ++i) {
    const auto& b = c.branches[i];
    for (const auto& [node, p] :
         {std::pair{table[i].from_node, b.points.front()}, std::pair{table[i].to_node, b.points.back()}}) {
      auto [it, fresh] = at.emplace(node, p);
      if (!fresh) {
        EXPECT_EQ((it->second - p).norm(), 0.0) << table[i].name << " at node " << node;
      }
    }
  }
  EXPECT_EQ(at.size(), 30u);
  // Distinct nodes are well apart (no accidental joins).
  for (auto a = at.begin(); a != at.end(); ++a)
    for (auto b = std::next(a); b != at.end(); ++b)
      EXPECT_GT((a->second - b->second).norm(), 1e-3) << "nodes " << a->first << " and " << b->first;
  // The circle of Willis: ICA II, A1, ACoA, A1, ICA II, PCoA, P1, P1, PCoA close a ring.
  auto ends = [&](const std::string& n) {
    const auto& b = branch(c, n);
    return std::pair{b.points.front(), b.points.back()};
  };
  EXPECT_EQ(ends("anterior_communicating").first, ends("left_anterior_cerebral_a1").second);
  EXPECT_EQ(ends("anterior_communicating").second, ends("right_anterior_cerebral_a1").second);
  EXPECT_EQ(ends("left_posterior_communicating").second, ends("left_internal_carotid_2").first);
  EXPECT_EQ(ends("left_posterior_communicating").first, ends("left_posterior_cerebral_p1").second);
  EXPECT_EQ(ends("right_posterior_cerebral_p1").first, ends("left_posterior_cerebral_p1").first);
  EXPECT_EQ(ends("left_vertebral").second, ends("right_vertebral").second);
  EXPECT_EQ(ends("basilar").first, ends("left_vertebral").second);
}

TEST(ArterialTree, LayoutIsAnatomicallyOriented) {
  const Centerlines c = arterial_tree();
  // Thoracic aorta runs down, brachials sideways (right: −x, left: +x), the circle above.
  const auto& thoracic = branch(c, "thoracic_aorta");
  EXPECT_LT(thoracic.points.back().z(), thoracic.points.front().z() - 0.1);
  EXPECT_LT(branch(c, "right_brachial").points.back().x(), -0.3);
  EXPECT_GT(branch(c, "left_brachial").points.back().x(), 0.3);
  const double circle_z = branch(c, "anterior_communicating").points.front().z();
  EXPECT_GT(circle_z, 0.15);
  EXPECT_GT(branch(c, "basilar").points.back().z(), branch(c, "basilar").points.front().z());
}

TEST(ArterialTree, ScaleMultipliesLengthsAndRadii) {
  const Centerlines a = arterial_tree();
  const Centerlines b = arterial_tree({.scale = 0.5});
  ASSERT_EQ(a.branches.size(), b.branches.size());
  for (size_t i = 0; i < a.branches.size(); ++i) {
    EXPECT_NEAR(arc_length(b.branches[i]), 0.5 * arc_length(a.branches[i]), 1e-14);
    ASSERT_EQ(a.branches[i].radii.size(), b.branches[i].radii.size());
    for (size_t k = 0; k < a.branches[i].radii.size(); ++k)
      EXPECT_NEAR(b.branches[i].radii[k], 0.5 * a.branches[i].radii[k], 1e-16);
  }
  const auto k = Network::build(b).counts();
  EXPECT_EQ(k.loops, 4);
  EXPECT_EQ(k.ends, 12);
  EXPECT_THROW((void)arterial_tree({.scale = 0.0}), Error);
  EXPECT_THROW((void)arterial_tree({.scale = -1.0}), Error);
}

TEST(ArterialTree, TerminalResistancesAndCompliances) {
  const auto rt = arterial_tree_terminal_resistances();
  const auto ct = arterial_tree_terminal_compliances();
  ASSERT_EQ(rt.size(), 11u);
  ASSERT_EQ(ct.size(), 11u);
  // Exactly the vessels ending at a node of degree one carry terminal data.
  const auto table = arterial_tree_vessels();
  std::map<int, int> degree;
  for (const auto& v : table) {
    ++degree[v.from_node];
    ++degree[v.to_node];
  }
  std::set<std::string> terminal;
  for (const auto& v : table)
    if (degree[v.to_node] == 1) terminal.insert(v.name);
  std::set<std::string> listed;
  for (size_t i = 0; i < rt.size(); ++i) {
    listed.insert(rt[i].first);
    EXPECT_EQ(rt[i].first, ct[i].first);
    EXPECT_GT(rt[i].second, 0.0);
    EXPECT_GT(ct[i].second, 0.0);
  }
  EXPECT_EQ(listed, terminal);
  const std::map<std::string, double> r(rt.begin(), rt.end()), cc(ct.begin(), ct.end());
  EXPECT_DOUBLE_EQ(r.at("thoracic_aorta"), 0.18e9);
  EXPECT_DOUBLE_EQ(r.at("left_external_carotid"), 5.43e9);
  EXPECT_DOUBLE_EQ(r.at("right_brachial"), 2.68e9);
  EXPECT_DOUBLE_EQ(r.at("left_middle_cerebral"), 5.97e9);
  EXPECT_DOUBLE_EQ(r.at("right_anterior_cerebral_a2"), 8.48e9);
  EXPECT_DOUBLE_EQ(r.at("left_posterior_cerebral_p2"), 11.08e9);
  EXPECT_DOUBLE_EQ(cc.at("thoracic_aorta"), 38.7e-10);
  EXPECT_DOUBLE_EQ(cc.at("right_posterior_cerebral_p2"), 0.62e-10);
}

}  // namespace
}  // namespace flowire::vessels
