#pragma once
/// @file element.hpp
/// @brief The reference P2 / P1 elements of flowire/common/element.hpp under the FEM's names.
#include "flowire/common/element.hpp"

namespace flowire::flow::fem {

using element::kTetEdges;
using element::kTriEdges;
using element::QuadPoint;
using element::tet_p1;
using element::tet_p2;
using element::tet_p2_grad;
using element::tet_p2_hessian;
using element::tet_quadrature;
using element::tri_p2;
using element::tri_p2_grad;
using element::tri_quadrature;

}  // namespace flowire::flow::fem
