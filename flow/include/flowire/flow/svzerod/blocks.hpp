#pragma once
/// @file blocks.hpp
/// @brief The svZeroDSolver block types flowire simulates, one class each. Every class
/// lists its governing equations (residual form, rows in order), its parameters by their
/// JSON names and its own unknowns. P, Q: pressure and flow of a connection; "in"/"out":
/// the block's inlet and outlet connections. A parameter is a number or a table over `t`.
#include "flowire/flow/svzerod/block.hpp"

namespace flowire::flow::svzerod {

/// @brief `BloodVessel` (vessels, `zero_d_element_values`): R and stenosis, then L, with C at the inlet.
/// \f[ P_{in} - P_{out} - (R + S|Q_{in}|)\,Q_{in} - L\,\dot Q_{out} = 0 \f]
/// \f[ Q_{in} - Q_{out} - C\,\frac{d}{dt}\left(P_{in} - (R + S|Q_{in}|)\,Q_{in}\right) = 0 \f]
/// Parameters: `R_poiseuille` (required), `C`, `L`, `stenosis_coefficient` S (default 0).
/// Nonlinear when S ≠ 0.
class BloodVessel : public Block {
 public:
  explicit BloodVessel(BlockInput& in);
  [[nodiscard]] const char* type() const override { return "BloodVessel"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] int num_equations() const override { return 2; }
  void assemble(Assembler& a, double t) const override;
  void assemble_nonlinear(Assembler& a, double t, const Eigen::VectorXd& y, const Eigen::VectorXd& yd) const override;
  [[nodiscard]] bool nonlinear() const override { return !(s_.constant() && s_.get(0.0) == 0.0); }

 private:
  Param r_, c_, l_, s_;
};

/// @brief `BloodVesselCRL`: C at the inlet, then R (with stenosis) and L.
/// \f[ P_{in} - P_{out} - (R + S|Q_{out}|)\,Q_{out} - L\,\dot Q_{out} = 0 \f]
/// \f[ Q_{in} - Q_{out} - C\,\dot P_{in} = 0 \f]
/// Parameters as BloodVessel.
class BloodVesselCRL : public Block {
 public:
  explicit BloodVesselCRL(BlockInput& in);
  [[nodiscard]] const char* type() const override { return "BloodVesselCRL"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] int num_equations() const override { return 2; }
  void assemble(Assembler& a, double t) const override;
  void assemble_nonlinear(Assembler& a, double t, const Eigen::VectorXd& y, const Eigen::VectorXd& yd) const override;
  [[nodiscard]] bool nonlinear() const override { return !(s_.constant() && s_.get(0.0) == 0.0); }

 private:
  Param r_, c_, l_, s_;
};

/// @brief `NORMAL_JUNCTION` (junctions): equal pressures and conserved flow at connections 0..n−1
/// (inlets first):
/// \f[ P_0 - P_i = 0,\ i = 1..n-1, \qquad \sum_{in} Q - \sum_{out} Q = 0 \f]
/// When the model gave all its connections one pressure unknown (equal_pressures()), only the
/// last row. No parameters.
class Junction : public Block {
 public:
  explicit Junction(BlockInput& in);
  [[nodiscard]] const char* type() const override { return "NORMAL_JUNCTION"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] bool equal_pressures() const override { return true; }
  [[nodiscard]] int num_equations() const override;
  void assemble(Assembler& a, double t) const override;

 private:
  /// True when every connection has the pressure unknown of the first.
  [[nodiscard]] bool shared_pressure() const;
};

/// @brief `BloodVesselJunction` (junctions, `junction_values`): one inlet, per outlet i an R, L, S branch:
/// \f[ Q_{in} - \sum_i Q_i = 0, \qquad P_{in} - P_i - (R_i + S_i|Q_i|)\,Q_i - L_i\,\dot Q_i = 0 \f]
/// Parameters: lists `R_poiseuille`, `L`, `stenosis_coefficient`, one value per outlet.
class BloodVesselJunction : public Block {
 public:
  explicit BloodVesselJunction(BlockInput& in);
  [[nodiscard]] const char* type() const override { return "BloodVesselJunction"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] int num_equations() const override { return 1 + static_cast<int>(outlets_.size()); }
  void assemble(Assembler& a, double t) const override;
  void assemble_nonlinear(Assembler& a, double t, const Eigen::VectorXd& y, const Eigen::VectorXd& yd) const override;
  [[nodiscard]] bool nonlinear() const override;

 private:
  std::vector<double> r_, l_, s_;
};

/// @brief `FLOW` (boundary conditions, `bc_values`): prescribed flow \f$ Q - Q(t) = 0 \f$.
/// Parameter: `Q`.
class FlowBC : public Block {
 public:
  explicit FlowBC(BlockInput& in);
  [[nodiscard]] const char* type() const override { return "FLOW"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] int num_equations() const override { return 1; }
  void assemble(Assembler& a, double t) const override;

 private:
  Param q_;
};

/// @brief `PRESSURE`: prescribed pressure \f$ P - P(t) = 0 \f$. Parameter: `P`.
class PressureBC : public Block {
 public:
  explicit PressureBC(BlockInput& in);
  [[nodiscard]] const char* type() const override { return "PRESSURE"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] int num_equations() const override { return 1; }
  void assemble(Assembler& a, double t) const override;

 private:
  Param p_;
};

/// @brief `RESISTANCE`: \f$ P - R\,Q - P_d = 0 \f$. Parameters: `R`, `Pd` (default 0).
class ResistanceBC : public Block {
 public:
  explicit ResistanceBC(BlockInput& in);
  [[nodiscard]] const char* type() const override { return "RESISTANCE"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] int num_equations() const override { return 1; }
  void assemble(Assembler& a, double t) const override;

 private:
  Param r_, pd_;
};

/// @brief `RCR` windkessel, own unknown \f$ P_c \f$ (`pressure_c:NAME`), the capacitor pressure:
/// \f[ P - R_p\,Q - P_c = 0, \qquad R_d\,Q - P_c - R_d C\,\dot P_c + P_d = 0 \f]
/// In the steady initial phase C = 0. Parameters: `Rp`, `C`, `Rd`, `Pd` (default 0).
class RcrBC : public Block {
 public:
  explicit RcrBC(BlockInput& in);
  [[nodiscard]] const char* type() const override { return "RCR"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] int num_equations() const override { return 2; }
  [[nodiscard]] std::vector<std::string> internal_unknowns() const override { return {"pressure_c"}; }
  void assemble(Assembler& a, double t) const override;
  [[nodiscard]] double time_constant() const override { return rd_.get(0.0) * c_.get(0.0); }

 private:
  Param rp_, c_, rd_, pd_;
};

/// @brief Open-loop `CORONARY` outlet: \f$ R_a \f$, \f$ C_a \f$, \f$ R_{am} \f$, \f$ C_{im} \f$
/// against the intramyocardial pressure \f$ P_{im}(t) \f$, \f$ R_v \f$ to \f$ P_v \f$; own unknown
/// \f$ V_{im} \f$ (`volume_im:NAME`). With the constants \f$ P_{im,0} \f$, \f$ P_{cim,0} \f$ of the
/// state the pulsatile phase starts from:
/// \f[ C_{im}R_v Q - V_{im} - C_aC_{im}R_v\dot P + R_aC_aC_{im}R_v\dot Q - C_{im}R_v\dot V_{im}
///     + C_{im}(P_v - P_{im} + P_{im,0} - P_{cim,0}) = 0 \f]
/// \f[ C_{im}R_v P - C_{im}R_vR_a Q - (R_v + R_{am})V_{im} - C_{im}R_vR_{am}\dot V_{im}
///     + R_{am}C_{im}P_v - C_{im}(R_v + R_{am})(P_{im} + P_{cim,0} - P_{im,0}) = 0 \f]
/// Steady initial phase: \f$ V_{im} = 0 \f$, \f$ P = (R_a + R_{am} + R_v)Q + P_v \f$.
/// Parameters: `Ra1` (\f$R_a\f$), `Ra2` (\f$R_{am}\f$), `Rv1`, `Ca`, `Cc` (\f$C_{im}\f$), `Pim`, `P_v`.
/// `CORONARY_VAR_RES`: instead of `Ra2`, `Ra2_min`, `Ra2_max`, `T_vc`, `T_vr`:
/// \f$ \sqrt{R_{am}} = \sqrt{R_{min}} + (\sqrt{R_{max}} - \sqrt{R_{min}})\,e(t) \f$ with the cosine
/// contraction ramp \f$ e = (1 - \cos(\pi t_c/T_{vc}))/2 \f$ for \f$ t_c \le T_{vc} \f$ and relaxation
/// ramp \f$ e = (1 + \cos(\pi (t_c - T_{vc})/T_{vr}))/2 \f$ up to \f$ T_{vc} + T_{vr} \f$, 0 after
/// (\f$ t_c \f$: time within the cycle).
class CoronaryBC : public Block {
 public:
  CoronaryBC(BlockInput& in, bool variable_resistance);
  [[nodiscard]] const char* type() const override { return varres_ ? "CORONARY_VAR_RES" : "CORONARY"; }
  [[nodiscard]] std::string check_connections() const override;
  [[nodiscard]] int num_equations() const override { return 2; }
  [[nodiscard]] std::vector<std::string> internal_unknowns() const override { return {"volume_im"}; }
  void assemble(Assembler& a, double t) const override;
  void prepare(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, bool after_steady, double period) override;
  /// @brief \f$ R_{am} \f$ at time t.
  [[nodiscard]] double ram(double t, bool steady, double period) const;

 private:
  bool varres_;
  Param ra_, rv_, ca_, cim_, pim_, pv_;
  Param ram_;                              // CORONARY
  Param ram_min_, ram_max_, t_vc_, t_vr_;  // CORONARY_VAR_RES
  double pim0_ = 0.0, pcim0_ = 0.0;
};

}  // namespace flowire::flow::svzerod
