#pragma once
/// @file lumen.hpp
/// @brief A scene's lumen surface (`vessels.surface`) and its entry introducer.
#include <memory>
#include <nlohmann/json.hpp>

#include "flowire/common/config.hpp"
#include "flowire/vessels/network.hpp"
#include "flowire/vessels/surface.hpp"

namespace flowire::coupling {

/// @brief The scene's lumen surface, or null without `vessels.surface`.
///
/// Read in the scene's `vessels.length_unit`; planar caps at the network's ends are removed
/// (a capped model is open there as the vessel is: the wire and the blood pass); oriented by
/// the network's interior nodes (inside the lumen). @p info receives its counts, @p smoothing
/// the contact's smoothing width (`vessels.surface_smoothing`, default
/// default_surface_smoothing()).
/// @throws flowire::Error (input) naming the file.
std::unique_ptr<vessels::LumenSurface> make_scene_surface(const config::Config& scene, const vessels::Network& net,
                                                          nlohmann::json& info, double& smoothing);

/// @brief The default width σ of a surface's smooth distance (LumenSurface::smooth_distance):
/// 0.4 of its mean edge length ℓ. Neighbouring triangles' planes then blend over about a
/// seventh of an edge (σ²/(2·0.58ℓ), centroids 0.58ℓ apart), smooth enough for Newton on the
/// real anatomies (no unconverged step), and d_σ weighs about a dozen triangles; its bias on a
/// wall of radius R, σ²/4R, is second order.
double default_surface_smoothing(const vessels::LumenSurface& surface);

}  // namespace flowire::coupling
