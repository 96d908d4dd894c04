#include "flowire/rod/energies.hpp"

#include "flowire/common/kernel_clones.hpp"

#include <cassert>
#include <cmath>
#include <numbers>

namespace flowire::rod {

namespace {

using Vec8 = Eigen::Matrix<double, 8, 1>;
using Mat8 = Eigen::Matrix<double, 8, 8>;
using Mat36 = Eigen::Matrix<double, 3, 6>;

Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

/// Geometry of a stencil at the base point. Variables "y" are (t_e, t_f, θ_e, θ_f).
struct Local {
  Vec3 te, tf;
  double le = 1.0, lf = 1.0;
  Vec3 m1e, m2e, m1f, m2f;  // material directors (frames transported to te, tf)
  Vec3 kb;
  double chi = 2.0;  // 1 + te·tf
  Mat36 dkb;         // ∂(κb)/∂(te, tf)
  double ref_twist = 0.0;
};

void finish_local(Local& L, bool need_dkb);

Local make_local(const VertexStencil& s, bool need_dkb) {
  Local L;
  const Vec3 e = s.x1 - s.x0;
  const Vec3 f = s.x2 - s.x1;
  L.le = e.norm();
  L.lf = f.norm();
  L.te = e / L.le;
  L.tf = f / L.lf;
  const Vec3 te0 = s.frame_e.d1.cross(s.frame_e.d2);
  const Vec3 tf0 = s.frame_f.d1.cross(s.frame_f.d2);
  // Frames already at the current tangents (the simulator's case): no transport needed.
  const bool at_base = (te0 - L.te).squaredNorm() < 1e-26 && (tf0 - L.tf).squaredNorm() < 1e-26;
  const Vec3 d1e = at_base ? s.frame_e.d1 : parallel_transport(s.frame_e.d1, te0, L.te);
  const Vec3 d2e = at_base ? s.frame_e.d2 : parallel_transport(s.frame_e.d2, te0, L.te);
  const Vec3 d1f = at_base ? s.frame_f.d1 : parallel_transport(s.frame_f.d1, tf0, L.tf);
  const Vec3 d2f = at_base ? s.frame_f.d2 : parallel_transport(s.frame_f.d2, tf0, L.tf);
  const double ce = std::cos(s.theta_e), se = std::sin(s.theta_e);
  const double cf = std::cos(s.theta_f), sf = std::sin(s.theta_f);
  L.m1e = ce * d1e + se * d2e;
  L.m2e = -se * d1e + ce * d2e;
  L.m1f = cf * d1f + sf * d2f;
  L.m2f = -sf * d1f + cf * d2f;
  L.ref_twist = at_base ? s.ref_twist : reference_twist(d1e, L.te, d1f, L.tf, s.ref_twist);
  finish_local(L, need_dkb);
  return L;
}

void finish_local(Local& L, bool need_dkb) {
  L.chi = 1.0 + L.te.dot(L.tf);
  const Vec3 w = L.te.cross(L.tf);
  L.kb = 2.0 * w / L.chi;
  if (need_dkb) {
    const double c = L.chi;
    L.dkb.leftCols<3>() = -(2.0 / c) * skew(L.tf) - (2.0 / (c * c)) * w * L.tf.transpose();
    L.dkb.rightCols<3>() = (2.0 / c) * skew(L.te) - (2.0 / (c * c)) * w * L.te.transpose();
  }
}

/// Add the Hessian of s = v·(κb) w.r.t. (te, tf), for a fixed vector v, to the top-left
/// 6×6 block of @p H. With N = v·(te × tf), χ = 1 + te·tf, gN = ∇N, gc = ∇χ:
/// ∇²s = (2/χ)∇²N − (2/χ²)(gN gcᵀ + gc gNᵀ) − (2N/χ²)∇²χ + (4N/χ³) gc gcᵀ
///     = u gcᵀ + gc uᵀ + (off-diagonal blocks), u = −(2/χ²) gN + (2N/χ³) gc.
void add_hessian_v_dot_kb(const Local& L, const Vec3& v, Mat8& H) {
  const double c = L.chi;
  const double N = v.dot(L.te.cross(L.tf));
  const double ic = 1.0 / c, ic2 = ic * ic;
  Vec6 gc;
  gc << L.tf, L.te;
  Vec6 u;
  u << -2.0 * ic2 * L.tf.cross(v), -2.0 * ic2 * v.cross(L.te);
  u += (2.0 * N * ic2 * ic) * gc;
  H.topLeftCorner<6, 6>().noalias() += u * gc.transpose() + gc * u.transpose();
  // (2/χ) ∇²N: ∂²N/∂te∂tf = −[v]×; −(2N/χ²) ∇²χ: ∂²χ/∂te∂tf = I.
  const Mat3 off = -(2.0 * ic) * skew(v) - (2.0 * N * ic2) * Mat3::Identity();
  H.block<3, 3>(0, 3) += off;
  H.block<3, 3>(3, 0) += off.transpose();
}

/// Gradient in y = (te, tf, θe, θf) of the material curvatures:
/// κ₁ = ½ (m2e + m2f)·κb (m2' = −m1), κ₂ = −½ (m1e + m1f)·κb (m1' = m2).
void curvature_gradients(const Local& L, Vec8& g1, Vec8& g2) {
  g1.head<6>() = 0.5 * (L.dkb.transpose() * (L.m2e + L.m2f));
  g1(6) = -0.5 * L.kb.dot(L.m1e);
  g1(7) = -0.5 * L.kb.dot(L.m1f);
  g2.head<6>() = -0.5 * (L.dkb.transpose() * (L.m1e + L.m1f));
  g2(6) = -0.5 * L.kb.dot(L.m2e);
  g2(7) = -0.5 * L.kb.dot(L.m2f);
}

/// Σ_k w_k ∇²κ_k in y. Every term g = κb·u(d) of a curvature is linear in its director d
/// (transported in time with its edge; d'' = −d), so the weighted sum collapses to one
/// director combination per edge:
///   D_e = ½ w₁ m2e − ½ w₂ m1e,  D'_e = −½ w₁ m1e − ½ w₂ m2e  (likewise for f),
/// and ∇²g = ∇²(v·κb)|_{v=D_e+D_f} + Kᵀ U + Uᵀ K + (transport terms), with U = ∂u/∂y.
void add_curvature_hessians(const Local& L, double w1, double w2, Mat8& H) {
  const Vec3 De = 0.5 * w1 * L.m2e - 0.5 * w2 * L.m1e;
  const Vec3 Dpe = -0.5 * w1 * L.m1e - 0.5 * w2 * L.m2e;
  const Vec3 Df = 0.5 * w1 * L.m2f - 0.5 * w2 * L.m1f;
  const Vec3 Dpf = -0.5 * w1 * L.m1f - 0.5 * w2 * L.m2f;
  add_hessian_v_dot_kb(L, De + Df, H);
  const Vec3* D[2] = {&De, &Df};
  const Vec3* Dp[2] = {&Dpe, &Dpf};
  const Vec3* T[2] = {&L.te, &L.tf};
  for (int edge = 0; edge < 2; ++edge) {
    const int tcol = 3 * edge, acol = 6 + edge;
    const Vec6 p = L.dkb.transpose() * (*T[edge]);   // Kᵀ t
    const Vec6 q = L.dkb.transpose() * (*Dp[edge]);  // Kᵀ d'
    const Eigen::Matrix<double, 6, 3> pd = -p * D[edge]->transpose();
    H.block<6, 3>(0, tcol) += pd;
    H.block<3, 6>(tcol, 0) += pd.transpose();
    H.block<6, 1>(0, acol) += q;
    H.block<1, 6>(acol, 0) += q.transpose();
    H.block<3, 3>(tcol, tcol) -= 0.5 * ((*D[edge]) * L.kb.transpose() + L.kb * D[edge]->transpose());
    H(acol, acol) -= L.kb.dot(*D[edge]);  // κb·d'' with d'' = −d
  }
}

/// Second derivative of t = e/|e| contracted with p: Σ_k p_k ∂²t_k/∂e².
Mat3 tangent_curvature_term(const Vec3& p, const Vec3& t, double l) {
  const double pt = p.dot(t);
  return -(t * p.transpose() + p * t.transpose() + pt * (Mat3::Identity() - 3.0 * t * t.transpose())) / (l * l);
}

/// Chain rule from y = (te, tf, θe, θf) to the stencil unknowns (x0, θe, x1, θf, x2),
/// with te depending on (x0, x1) through Pe = (I − te teᵀ)/le and tf on (x1, x2).
void to_stencil(const Local& L, const Vec8& gy, const Mat8* Hy, Vec11* gx, Mat11* Hx, bool first_order_only = false) {
  const Mat3 Pe = (Mat3::Identity() - L.te * L.te.transpose()) / L.le;
  const Mat3 Pf = (Mat3::Identity() - L.tf * L.tf.transpose()) / L.lf;
  if (gx) {
    const Vec3 ge = Pe * gy.segment<3>(0);
    const Vec3 gf = Pf * gy.segment<3>(3);
    gx->segment<3>(0) = -ge;
    (*gx)(3) = gy(6);
    gx->segment<3>(4) = ge - gf;
    (*gx)(7) = gy(7);
    gx->segment<3>(8) = gf;
  }
  if (Hx && Hy) {
    const Mat8& h = *Hy;
    Mat3 Ee = Pe * h.block<3, 3>(0, 0) * Pe;
    const Mat3 Ef = Pe * h.block<3, 3>(0, 3) * Pf;
    Mat3 Ff = Pf * h.block<3, 3>(3, 3) * Pf;
    if (!first_order_only) {
      Ee += tangent_curvature_term(gy.segment<3>(0), L.te, L.le);
      Ff += tangent_curvature_term(gy.segment<3>(3), L.tf, L.lf);
    }
    Mat11& H = *Hx;
    H.block<3, 3>(0, 0) = Ee;
    H.block<3, 3>(0, 4) = Ef - Ee;
    H.block<3, 3>(0, 8) = -Ef;
    H.block<3, 3>(4, 4) = Ee - Ef - Ef.transpose() + Ff;
    H.block<3, 3>(4, 8) = Ef - Ff;
    H.block<3, 3>(8, 8) = Ff;
    H.block<3, 3>(4, 0) = H.block<3, 3>(0, 4).transpose();
    H.block<3, 3>(8, 0) = H.block<3, 3>(0, 8).transpose();
    H.block<3, 3>(8, 4) = H.block<3, 3>(4, 8).transpose();
    const int acol[2] = {3, 7};
    for (int a = 0; a < 2; ++a) {
      const Vec3 ue = Pe * h.block<3, 1>(0, 6 + a);
      const Vec3 uf = Pf * h.block<3, 1>(3, 6 + a);
      const int c = acol[a];
      H.block<3, 1>(0, c) = -ue;
      H.block<3, 1>(4, c) = ue - uf;
      H.block<3, 1>(8, c) = uf;
      H.block<1, 3>(c, 0) = -ue.transpose();
      H.block<1, 3>(c, 4) = (ue - uf).transpose();
      H.block<1, 3>(c, 8) = uf.transpose();
    }
    H(3, 3) = h(6, 6);
    H(3, 7) = H(7, 3) = h(6, 7);
    H(7, 7) = h(7, 7);
  }
}

/// Bending energy with gradient/Hessian in y.
double bend_y(const Local& L, const VertexParams& p, Vec8* gy, Mat8* Hy, bool gn = false) {
  const double k1 = 0.5 * (L.m2e + L.m2f).dot(L.kb);
  const double k2 = -0.5 * (L.m1e + L.m1f).dot(L.kb);
  const double d1 = k1 - p.rest_kappa1, d2 = k2 - p.rest_kappa2;
  const double c1 = p.bend_stiffness1 / p.voronoi_length;
  const double c2 = p.bend_stiffness2 / p.voronoi_length;
  if (gy || Hy) {
    Vec8 g1, g2;
    curvature_gradients(L, g1, g2);
    if (gy) *gy += c1 * d1 * g1 + c2 * d2 * g2;
    if (Hy) {
      *Hy += c1 * g1 * g1.transpose() + c2 * g2 * g2.transpose();
      if (!gn) add_curvature_hessians(L, c1 * d1, c2 * d2, *Hy);
    }
  }
  return 0.5 * (c1 * d1 * d1 + c2 * d2 * d2);
}

/// Twisting energy with gradient/Hessian in y.
double twist_y(const Local& L, double theta_e, double theta_f, const VertexParams& p, Vec8* gy, Mat8* Hy,
               bool gn = false) {
  const double m = theta_f - theta_e + L.ref_twist;
  const double dm = m - p.rest_twist;
  const double c = p.twist_stiffness / p.voronoi_length;
  Vec8 gm;
  gm << 0.5 * L.kb, 0.5 * L.kb, -1.0, 1.0;
  if (gy) *gy += c * dm * gm;
  if (Hy && gn) *Hy += c * gm * gm.transpose();
  if (Hy && !gn) {
    // m_ref = m⁰ − Ω₁(te⁰, te, tf) − Ω₂(te⁰, tf, tf⁰) at the base point te = te⁰, tf = tf⁰.
    // With D = 2χ, n = tf × te, gD = te + tf, the Hessian of m_ref is −H_A,
    // H_A = (2/D) ∇²N₁ − (2/D²)(∇N₁ ∇D₁ᵀ + ∇D₁ ∇N₁ᵀ) − (2/D²)(n gDᵀ + gD nᵀ) on (tf, tf),
    // ∇N₁ = (n, 0), ∇D₁ = (gD, 2te), ∂²N₁/∂te∂tf = −[te]×; added as c·dm·(−H_A).
    *Hy += c * gm * gm.transpose();
    const double D = 2.0 * L.chi;
    const double s = c * dm;
    const double beta = 2.0 * s / (D * D);
    const Vec3 n = L.tf.cross(L.te);
    const Vec3 gD = L.te + L.tf;
    const Mat3 sym_n_gD = beta * (n * gD.transpose() + gD * n.transpose());
    const Mat3 cross = (2.0 * beta) * n * L.te.transpose() + (2.0 * s / D) * skew(L.te);
    Hy->block<3, 3>(0, 0) += sym_n_gD;
    Hy->block<3, 3>(3, 3) += sym_n_gD;
    Hy->block<3, 3>(0, 3) += cross;
    Hy->block<3, 3>(3, 0) += cross.transpose();
  }
  return 0.5 * c * dm * dm;
}

// Small value types for the stencil kernel below: plain structs of doubles that the compiler
// keeps in registers and inlines completely (fixed-size Eigen 3-vectors in an expression of
// this size end up as out-of-line assignment loops).
struct V3 {
  double x, y, z;
};
[[gnu::always_inline]] inline V3 v3(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
[[gnu::always_inline]] inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
[[gnu::always_inline]] inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
[[gnu::always_inline]] inline V3 operator-(V3 a) { return {-a.x, -a.y, -a.z}; }
[[gnu::always_inline]] inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
[[gnu::always_inline]] inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
[[gnu::always_inline]] inline V3 cross(V3 a, V3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
[[gnu::always_inline]] inline double at(V3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }

/// 3×3 matrix, row-major.
struct M3 {
  double m[3][3];
};
/// A += s a bᵀ
[[gnu::always_inline]] inline void add_outer(M3& A, double s, V3 a, V3 b) {
  const V3 sa = s * a;
  for (int i = 0; i < 3; ++i) {
    const double ai = at(sa, i);
    A.m[i][0] += ai * b.x;
    A.m[i][1] += ai * b.y;
    A.m[i][2] += ai * b.z;
  }
}
/// Symmetric 3×3 matrix (upper triangle).
struct S3 {
  double xx, yy, zz, xy, xz, yz;
};
/// S += s a aᵀ
[[gnu::always_inline]] inline void add_sym_outer(S3& S, double s, V3 a) {
  const V3 sa = s * a;
  S.xx += sa.x * a.x, S.yy += sa.y * a.y, S.zz += sa.z * a.z;
  S.xy += sa.x * a.y, S.xz += sa.x * a.z, S.yz += sa.y * a.z;
}
/// S += a bᵀ + b aᵀ
[[gnu::always_inline]] inline void add_sym2(S3& S, V3 a, V3 b) {
  S.xx += 2.0 * a.x * b.x, S.yy += 2.0 * a.y * b.y, S.zz += 2.0 * a.z * b.z;
  S.xy += a.x * b.y + a.y * b.x, S.xz += a.x * b.z + a.z * b.x, S.yz += a.y * b.z + a.z * b.y;
}
[[gnu::always_inline]] inline void scale(S3& S, double s) {
  S.xx *= s, S.yy *= s, S.zz *= s, S.xy *= s, S.xz *= s, S.yz *= s;
}
[[gnu::always_inline]] inline double get(const S3& S, int i, int j) {
  if (i == j) return i == 0 ? S.xx : (i == 1 ? S.yy : S.zz);
  const int k = i + j;  // 1: xy, 2: xz, 3: yz
  return k == 1 ? S.xy : (k == 2 ? S.xz : S.yz);
}

/// Bending plus twisting at the base point, written out for speed (the simulator calls it
/// for every interior vertex of every Newton matrix). The same function as bend_y + twist_y
/// + to_stencil, reorganised:
/// - ∂(κb)/∂(te, tf) is never formed; only its transpose applied to a vector is needed,
///   K(v) = (2/χ)(tf × v, v × te) − (2/χ²)(w·v)(tf, te), w = te × tf;
/// - the bending second-order terms use K(te) = (−κb, 0), K(tf) = (0, −κb), which turns
///   the transport terms of the tangent blocks into ½(κb Dᵀ + D κbᵀ);
/// - the y-space Hessian is never formed: its tangent blocks are sums of outer products of
///   3-vectors, and the chain rule through P = (I − t tᵀ)/ℓ projects those vectors (the
///   only 3×3 term, [r]× + δ I in (te,tf), is projected in closed form);
/// - the (x0,x0) and (x2,x2) blocks are built as symmetric 3×3 matrices, and the 11×11
///   result is written once, both triangles, from the three position blocks Ee, Ef, Ff.
FLOWIRE_KERNEL_CLONES
double bend_twist_kernel(const Vec3& te_, const Vec3& tf_, double le, double lf, const Vec3& m1e_, const Vec3& m2e_,
                         const Vec3& m1f_, const Vec3& m2f_, double theta_e, double theta_f, double ref_twist,
                         const VertexParams& p, Vec11* gradient, Mat11* hessian, bool gauss_newton) {
  const V3 te = v3(te_), tf = v3(tf_);
  const V3 m1e = v3(m1e_), m2e = v3(m2e_), m1f = v3(m1f_), m2f = v3(m2f_);
  const double chi = 1.0 + dot(te, tf);
  const double ic = 1.0 / chi;
  const V3 w = cross(te, tf);
  const V3 kb = (2.0 * ic) * w;
  const V3 m1s = m1e + m1f, m2s = m2e + m2f;
  const double d1 = 0.5 * dot(m2s, kb) - p.rest_kappa1;
  const double d2 = -0.5 * dot(m1s, kb) - p.rest_kappa2;
  const double c1 = p.bend_stiffness1 / p.voronoi_length;
  const double c2 = p.bend_stiffness2 / p.voronoi_length;
  const double ct = p.twist_stiffness / p.voronoi_length;
  const double dm = theta_f - theta_e + ref_twist - p.rest_twist;
  const double energy = 0.5 * (c1 * d1 * d1 + c2 * d2 * d2) + 0.5 * ct * dm * dm;
  if (gradient == nullptr && hessian == nullptr) return energy;

  const double s1 = c1 * d1, s2 = c2 * d2, st = ct * dm;
  const double two_ic = 2.0 * ic, two_ic2 = two_ic * ic;
  // (ke, kf) = ∂(κb)/∂(te, tf)ᵀ v.
  auto apply_kt = [&](V3 v, V3 & ke, V3 & kf) __attribute__((always_inline)) {
    const double wv = two_ic2 * dot(w, v);
    ke = two_ic * cross(tf, v) - wv * tf;
    kf = two_ic * cross(v, te) - wv * te;
  };
  // ∇κ₁ = (g1e, g1f, g1a, g1b), ∇κ₂ likewise, ∇m = (½κb, ½κb, −1, 1) in y = (te, tf, θe, θf).
  V3 g1e, g1f, g2e, g2f;
  apply_kt(0.5 * m2s, g1e, g1f);
  apply_kt(-0.5 * m1s, g2e, g2f);
  const double g1a = -0.5 * dot(kb, m1e), g1b = -0.5 * dot(kb, m1f);
  const double g2a = -0.5 * dot(kb, m2e), g2b = -0.5 * dot(kb, m2f);
  const V3 hk = 0.5 * kb;
  const V3 gye = s1 * g1e + s2 * g2e + st * hk;
  const V3 gyf = s1 * g1f + s2 * g2f + st * hk;
  const double gya = s1 * g1a + s2 * g2a - st;
  const double gyb = s1 * g1b + s2 * g2b + st;
  const double ile = 1.0 / le, ilf = 1.0 / lf;
  const double pte = dot(te, gye), ptf = dot(tf, gyf);
  if (gradient != nullptr) {
    const V3 ge = ile * (gye - pte * te);
    const V3 gf = ilf * (gyf - ptf * tf);
    double* g = gradient->data();
    g[0] = -ge.x, g[1] = -ge.y, g[2] = -ge.z;
    g[3] = gya;
    g[4] = ge.x - gf.x, g[5] = ge.y - gf.y, g[6] = ge.z - gf.z;
    g[7] = gyb;
    g[8] = gf.x, g[9] = gf.y, g[10] = gf.z;
  }
  if (hessian == nullptr) return energy;

  // Hessian. Every y-space term of the (te,te), (te,tf), (tf,tf) blocks is a sum of outer
  // products, so the projections P = (I − t tᵀ)/ℓ of the chain rule are applied to the
  // vectors (Q v = v − t (t·v), the 1/ℓ factors at the end) instead of to 3×3 matrices.
  // ½κb ∝ te × tf is orthogonal to both tangents and needs no projection.
  auto Qe = [&](V3 v) __attribute__((always_inline)) { return v - dot(te, v) * te; };
  auto Qf = [&](V3 v) __attribute__((always_inline)) { return v - dot(tf, v) * tf; };
  const V3 a1 = Qe(g1e), a2 = Qe(g2e), b1 = Qf(g1f), b2 = Qf(g2f);
  const double c1a = c1 * g1a, c2a = c2 * g2a, c1b = c1 * g1b, c2b = c2 * g2b;
  V3 ue6 = c1a * a1 + c2a * a2 - ct * hk;  // projected (te; θe), (te; θf) … columns
  V3 uf6 = c1a * b1 + c2a * b2 - ct * hk;
  V3 ue7 = c1b * a1 + c2b * a2 + ct * hk;
  V3 uf7 = c1b * b1 + c2b * b2 + ct * hk;
  double h66 = c1a * g1a + c2a * g2a + ct;
  double h67 = c1a * g1b + c2a * g2b - ct;
  double h77 = c1b * g1b + c2b * g2b + ct;
  // First-derivative products (all of the Gauss–Newton matrix).
  S3 Ee{}, Ff{};
  M3 Ef{};
  add_sym_outer(Ee, c1, a1);
  add_sym_outer(Ee, c2, a2);
  add_sym_outer(Ee, ct, hk);
  add_sym_outer(Ff, c1, b1);
  add_sym_outer(Ff, c2, b2);
  add_sym_outer(Ff, ct, hk);
  add_outer(Ef, c1, a1, b1);
  add_outer(Ef, c2, a2, b2);
  add_outer(Ef, ct, hk, hk);
  if (!gauss_newton) {
    // Bending: Σ_k s_k ∇²κ_k (see add_curvature_hessians) with the director combinations
    // D = ½ s₁ m2 − ½ s₂ m1, D' = −½ s₁ m1 − ½ s₂ m2 per edge and v = D_e + D_f.
    const V3 De = (0.5 * s1) * m2e - (0.5 * s2) * m1e;
    const V3 Df = (0.5 * s1) * m2f - (0.5 * s2) * m1f;
    const V3 Dpe = (-0.5 * s1) * m1e - (0.5 * s2) * m2e;
    const V3 Dpf = (-0.5 * s1) * m1f - (0.5 * s2) * m2f;
    const V3 v = De + Df;
    const double N = dot(v, w);
    const double b2n = N * two_ic2 * ic;
    const V3 ue = b2n * tf - two_ic2 * cross(tf, v);
    const V3 uf = b2n * te - two_ic2 * cross(v, te);
    // Twisting: the holonomy terms (see twist_y), n = tf × te, gD = te + tf.
    const double D = 2.0 * chi;
    const double beta = 2.0 * st / (D * D);
    const V3 n = -w;
    const double cte = chi - 1.0;   // te·tf
    const V3 tf_e = tf - cte * te;  // Qe tf = Qe gD
    const V3 te_f = te - cte * tf;  // Qf te = Qf gD
    const V3 uqe = Qe(ue), uqf = Qf(uf);
    // (te,te): sym(ue, tf) + sym(½κb, De) + β sym(n, gD), projected, plus the second
    // derivative of te: −sym(te, p − 3/2 (p·te) te) − (p·te) I with p = ∂E/∂te.
    add_sym2(Ee, uqe + beta * n, tf_e);
    add_sym2(Ee, hk, Qe(De));
    add_sym2(Ee, -te, gye - (1.5 * pte) * te);
    Ee.xx -= pte, Ee.yy -= pte, Ee.zz -= pte;
    add_sym2(Ff, uqf + beta * n, te_f);
    add_sym2(Ff, hk, Qf(Df));
    add_sym2(Ff, -tf, gyf - (1.5 * ptf) * tf);
    Ff.xx -= ptf, Ff.yy -= ptf, Ff.zz -= ptf;
    // (te,tf): ue teᵀ + tf ufᵀ + 2β n teᵀ + M, M = [r]× + δ I, projected on both sides:
    // Qe M Qf = M − te (te × r + δ te)ᵀ − (r × tf + δ tf − γ te) tfᵀ, γ = te·(r × tf) + δ te·tf.
    add_outer(Ef, 1.0, uqe + (2.0 * beta) * n, te_f);
    add_outer(Ef, 1.0, tf_e, uqf);
    const V3 r = (2.0 * st / D) * te - two_ic * v;
    const double delta = -N * two_ic2;
    const V3 rtf = cross(r, tf);
    const double gamma = dot(te, rtf) + delta * cte;
    add_outer(Ef, -1.0, te, cross(te, r) + delta * te);
    add_outer(Ef, -1.0, rtf + delta * tf - gamma * te, tf);
    Ef.m[0][0] += delta;
    Ef.m[1][1] += delta;
    Ef.m[2][2] += delta;
    Ef.m[0][1] -= r.z;
    Ef.m[0][2] += r.y;
    Ef.m[1][0] += r.z;
    Ef.m[1][2] -= r.x;
    Ef.m[2][0] -= r.y;
    Ef.m[2][1] += r.x;
    V3 qe, qf;
    apply_kt(Dpe, qe, qf);
    ue6 = ue6 + Qe(qe);
    uf6 = uf6 + Qf(qf);
    apply_kt(Dpf, qe, qf);
    ue7 = ue7 + Qe(qe);
    uf7 = uf7 + Qf(qf);
    h66 -= dot(kb, De);
    h77 -= dot(kb, Df);
  }
  ue6 = ile * ue6, ue7 = ile * ue7, uf6 = ilf * uf6, uf7 = ilf * uf7;
  scale(Ee, ile * ile);
  scale(Ff, ilf * ilf);
  {
    const double sef = ile * ilf;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) Ef.m[i][j] *= sef;
  }

  // Blocks (x0,x0) = Ee, (x0,x1) = Ef − Ee, (x0,x2) = −Ef, (x1,x1) = Ee − Ef − Efᵀ + Ff,
  // (x1,x2) = Ef − Ff, (x2,x2) = Ff; written column-major with their transposes.
  double* h = hessian->data();
  auto set = [h](int r, int c, double v) __attribute__((always_inline)) {
    h[c * 11 + r] = v;
    h[r * 11 + c] = v;
  };
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double x01 = Ef.m[i][j] - get(Ee, i, j);
      const double x12 = Ef.m[i][j] - get(Ff, i, j);
      h[j * 11 + i] = get(Ee, i, j);
      h[(8 + j) * 11 + 8 + i] = get(Ff, i, j);
      h[(4 + j) * 11 + 4 + i] = (get(Ee, i, j) + get(Ff, i, j)) - (Ef.m[i][j] + Ef.m[j][i]);
      set(i, 4 + j, x01);
      set(i, 8 + j, -Ef.m[i][j]);
      set(4 + i, 8 + j, x12);
    }
    set(i, 3, -at(ue6, i));
    set(4 + i, 3, at(ue6, i) - at(uf6, i));
    set(8 + i, 3, at(uf6, i));
    set(i, 7, -at(ue7, i));
    set(4 + i, 7, at(ue7, i) - at(uf7, i));
    set(8 + i, 7, at(uf7, i));
  }
  h[3 * 11 + 3] = h66;
  set(3, 7, h67);
  h[7 * 11 + 7] = h77;
  return energy;
}

}  // namespace

Vec3 curvature_binormal(const Vec3& te, const Vec3& tf) { return 2.0 * te.cross(tf) / (1.0 + te.dot(tf)); }

double stretch_energy(const Vec3& x0, const Vec3& x1, double ks, double rest_length) {
  const double strain = (x1 - x0).norm() / rest_length - 1.0;
  return 0.5 * ks * rest_length * strain * strain;
}

Vec6 stretch_gradient(const Vec3& x0, const Vec3& x1, double ks, double rest_length) {
  const Vec3 e = x1 - x0;
  const double l = e.norm();
  const Vec3 g = ks * (l / rest_length - 1.0) * (e / l);
  Vec6 out;
  out << -g, g;
  return out;
}

Mat6 stretch_hessian(const Vec3& x0, const Vec3& x1, double ks, double rest_length, bool clamp_compression) {
  const Vec3 e = x1 - x0;
  const double l = e.norm();
  const Vec3 t = e / l;
  const Mat3 tt = t * t.transpose();
  double transverse = ks * (1.0 / rest_length - 1.0 / l);
  if (clamp_compression) transverse = std::max(transverse, 0.0);
  const Mat3 h = (ks / rest_length) * tt + transverse * (Mat3::Identity() - tt);
  Mat6 out;
  out << h, -h, -h, h;
  return out;
}

Eigen::Vector2d material_curvature(const VertexStencil& s) {
  const Local L = make_local(s, false);
  return {0.5 * (L.m2e + L.m2f).dot(L.kb), -0.5 * (L.m1e + L.m1f).dot(L.kb)};
}

double bend_energy(const VertexStencil& s, const VertexParams& p) {
  const Local L = make_local(s, false);
  return bend_y(L, p, nullptr, nullptr);
}

Vec11 bend_gradient(const VertexStencil& s, const VertexParams& p) {
  const Local L = make_local(s, true);
  Vec8 gy = Vec8::Zero();
  bend_y(L, p, &gy, nullptr);
  Vec11 g;
  to_stencil(L, gy, nullptr, &g, nullptr);
  return g;
}

Mat11 bend_hessian(const VertexStencil& s, const VertexParams& p) {
  const Local L = make_local(s, true);
  Vec8 gy = Vec8::Zero();
  Mat8 Hy = Mat8::Zero();
  bend_y(L, p, &gy, &Hy);
  Mat11 H;
  to_stencil(L, gy, &Hy, nullptr, &H);
  return H;
}

double twist(const VertexStencil& s) {
  const Local L = make_local(s, false);
  return s.theta_f - s.theta_e + L.ref_twist;
}

double twist_energy(const VertexStencil& s, const VertexParams& p) {
  const Local L = make_local(s, false);
  return twist_y(L, s.theta_e, s.theta_f, p, nullptr, nullptr);
}

Vec11 twist_gradient(const VertexStencil& s, const VertexParams& p) {
  const Local L = make_local(s, false);
  Vec8 gy = Vec8::Zero();
  twist_y(L, s.theta_e, s.theta_f, p, &gy, nullptr);
  Vec11 g;
  to_stencil(L, gy, nullptr, &g, nullptr);
  return g;
}

Mat11 twist_hessian(const VertexStencil& s, const VertexParams& p) {
  const Local L = make_local(s, false);
  Vec8 gy = Vec8::Zero();
  Mat8 Hy = Mat8::Zero();
  twist_y(L, s.theta_e, s.theta_f, p, &gy, &Hy);
  Mat11 H;
  to_stencil(L, gy, &Hy, nullptr, &H);
  return H;
}

double bend_twist(const VertexStencil& s, const VertexParams& p, Vec11* gradient, Mat11* hessian, bool gauss_newton) {
  const Local L = make_local(s, false);
  return bend_twist_kernel(L.te, L.tf, L.le, L.lf, L.m1e, L.m2e, L.m1f, L.m2f, s.theta_e, s.theta_f, L.ref_twist, p,
                           gradient, hessian, gauss_newton);
}

EdgeGeometry edge_geometry(const Vec3& x0, const Vec3& x1, const EdgeFrame& frame, double theta) {
  EdgeGeometry g;
  const Vec3 e = x1 - x0;
  g.length = e.norm();
  g.t = e / g.length;
  const double c = std::cos(theta), s = std::sin(theta);
  g.m1 = c * frame.d1 + s * frame.d2;
  g.m2 = -s * frame.d1 + c * frame.d2;
  return g;
}

double bend_twist(const EdgeGeometry& e, const EdgeGeometry& f, double theta_e, double theta_f, double ref_twist,
                  const VertexParams& p, Vec11* gradient, Mat11* hessian, bool gauss_newton) {
  return bend_twist_kernel(e.t, f.t, e.length, f.length, e.m1, e.m2, f.m1, f.m2, theta_e, theta_f, ref_twist, p,
                           gradient, hessian, gauss_newton);
}

namespace detail {

double bend_twist_reference(const EdgeGeometry& e, const EdgeGeometry& f, double theta_e, double theta_f,
                            double ref_twist, const VertexParams& p, Vec11* gradient, Mat11* hessian,
                            bool gauss_newton) {
  Local L;
  L.te = e.t;
  L.tf = f.t;
  L.le = e.length;
  L.lf = f.length;
  L.m1e = e.m1;
  L.m2e = e.m2;
  L.m1f = f.m1;
  L.m2f = f.m2;
  L.ref_twist = ref_twist;
  const bool derivatives = gradient != nullptr || hessian != nullptr;
  finish_local(L, derivatives);
  Vec8 gy = Vec8::Zero();
  Mat8 Hy = Mat8::Zero();
  Vec8* gp = derivatives ? &gy : nullptr;
  Mat8* hp = hessian ? &Hy : nullptr;
  double energy = bend_y(L, p, gp, hp, gauss_newton);
  energy += twist_y(L, theta_e, theta_f, p, gp, hp, gauss_newton);
  if (derivatives) to_stencil(L, gy, hp, gradient, hessian, gauss_newton);
  return energy;
}

}  // namespace detail

}  // namespace flowire::rod
