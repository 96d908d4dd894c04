#pragma once
/// @file arterial_tree.hpp
/// @brief Published data behind `arterial_tree()` (generators.hpp): the 33-artery network of
/// Alastruey, Parker, Peiró, Byrd & Sherwin 2007, "Modelling the circle of Willis to assess
/// the effects of anatomical variations and occlusions on cerebral flows", J. Biomech.
/// 40:1794–1805, Table 1. All values in SI units and unscaled (ArterialTreeParams::scale = 1).
///
/// Connectivity uses the paper's junction numbering: vessel `id` runs from node `from_node`
/// to node `to_node` (1 is the aortic root, the flow inlet). The network has 30 nodes,
/// 12 ends (the inlet and 11 terminal vessels) and 4 independent loops (33 − 30 + 1): the
/// vertebral arteries joining at the basilar artery close one through the subclavians and the
/// aortic arch; the circle of Willis itself (internal carotids II, A1 segments joined by the
/// anterior communicating artery, posterior communicating arteries, P1 segments) closes a
/// second; the left and right carotid paths into the circle close two more.
#include <string>
#include <utility>
#include <vector>

namespace flowire::vessels {

/// @brief One vessel of the network as published (Table 1 of Alastruey et al. 2007).
struct ArterialTreeVessel {
  int id = 0;                   ///< the paper's vessel number, 1..33
  std::string name;             ///< branch name used by `arterial_tree()`
  int from_node = 0;            ///< proximal junction (paper numbering, 1 = aortic root)
  int to_node = 0;              ///< distal junction or terminal
  double length = 0.0;          ///< m
  double radius_in = 0.0;       ///< proximal lumen radius (m)
  double radius_out = 0.0;      ///< distal lumen radius (m); the paper's vessels are uniform
  double wall_thickness = 0.0;  ///< m
  double young_modulus = 0.0;   ///< Pa
};

/// @brief The 33 vessels in the paper's order (ids 1..33).
std::vector<ArterialTreeVessel> arterial_tree_vessels();

/// @brief Peripheral resistance of each terminal vessel (Pa·s/m³), keyed by branch name, in
/// the paper's vessel order: thoracic aorta, external carotids, brachials, middle, anterior
/// (A2) and posterior (P2) cerebral arteries; 11 outlets. This is the total resistance of the
/// vascular bed beyond the outlet (Table 1, "R", 10⁹ Pa·s/m³ there). Unscaled.
std::vector<std::pair<std::string, double>> arterial_tree_terminal_resistances();

/// @brief Peripheral compliance of each terminal vessel (m³/Pa), same keys and order as
/// `arterial_tree_terminal_resistances()` (Table 1, "C", 10⁻¹⁰ m³/Pa there). Unscaled.
std::vector<std::pair<std::string, double>> arterial_tree_terminal_compliances();

}  // namespace flowire::vessels
