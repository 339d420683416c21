#pragma once
// Physically based reference melt of an ice body (issue 4 §1): the enthalpy method on a
// voxel grid (Grid3, core/grid3.h), explicit in time for conduction, point-implicit for the
// boundary exchange.
//
// Model
//   State per cell: the H2O content s in [0, 1] (volume fraction of the cell that holds ice
//   or retained meltwater, "substance fraction") and the enthalpy H per unit *cell* volume,
//   J/m³, relative to ice at the melting point T_m = 0 °C. With ρ the ice density (the water
//   keeps the ice's volume — the Neumann problem's equal-density assumption):
//     H < 0            : solid,  T = H / (s ρ c_ice)
//     0 <= H <= s ρ L  : mushy,  T = 0 °C, liquid fraction f_l = H / (s ρ L)
//     H > s ρ L        : liquid, T = (H - s ρ L) / (s ρ c_water)
//   Ice fraction of the cell (what the renderer sees) φ = s (1 - f_l).
//   Conduction between face neighbours: conductance K = min(s_a, s_b) · h · 2 k_a k_b/(k_a+k_b)
//   (two half cells in series, open area scaled by the smaller content), k = (1-f_l) k_ice +
//   f_l k_water in a cell.
//   Boundary of the body (diffuse interface): the body fraction b (the ice fraction φ when
//   meltwater drains — the retained water only stores and conducts heat, geometrically it has
//   drained —, the content s otherwise) is a smoothed indicator of the body. A face between
//   cells a, b with b_a != b_b
//   carries exposed surface area
//        A_face = h² |Δb| |n_axis|,   n = direction of the sum of the two cells' Sobel gradients
//                                         of b (3x3x3; (1,2,1) smoothing across the axis)
//   Along any grid line the |Δb| of a monotone crossing sum to 1, so Σ_x-faces h²|Δb| → ∫|n_x| dA,
//   and weighting by |n_x| (= |n·e_x|) gives Σ over the three axes → ∫(n_x²+n_y²+n_z²) dA = area:
//   the surface area converges with h, unlike the staircase area (which overestimates a sphere's
//   by ~50%), and it is insensitive to first order to errors of the normal estimate. The face's
//   heat goes to the outer cell if it holds H2O, else to the inner one. (Measured: a voxelized
//   sphere of r/h = 15 gets its area within 0.3%.)
//   Sub-cell bits: the diffuse area of a bit of ice thinner than a cell is ∝ b, which would
//   make the last bits melt in an exponential tail. So (a) a cell of layer 0 (on the ground)
//   with less body above it is a sheet whose top lacks h²(1 - b)(b - b_above)/b of upward
//   face (the whole face for nothing above, nothing for a vertical wall through the cell);
//   (b) elsewhere a cell with 0 < b < 1 that no face neighbour exceeds (an isolated chunk)
//   has its face areas scaled by b^{-1/3} (area ∝ b^{2/3}, a compact chunk's).
//   Fluxes on A_face (outward normal n = -∇b/|∇b|):
//     convection   h_c(n) (T_air - T_cell),  h_c blends h_up / h_vertical / h_down by n_z;
//     ambient long-wave radiation  h_r (T_air - T_cell), h_r = ε σ (T_a² + T_s²)(T_a + T_s)
//                  linearised about T_s = 0 °C (surface of melting ice), walls at T_air;
//     lamp         α q_lamp max(0, n · ℓ) (ℓ = unit direction towards the lamp; no shadowing).
//   Ground: the bottom face of layer k = 0 is in contact with a ground at T_ground through a
//   contact conductance G (W/m²/K, in series with half a cell of the body): area h² s (the
//   footprint of the cell's ice and retained meltwater).
//   G = +infinity makes it a Dirichlet wall (used for the Stefan problem).
//   Settling: the body rests on the ground; when layer 0 has melted away entirely the whole
//   body drops by whole cells (rigid; the grid stays fixed in the world, settled_m() reports
//   the drop). A body held up by a few remaining cells of layer 0 does not drop.
//   Other grid faces (x, y sides, top) are insulated; grids are built with a margin of air.
//   Drainage (drain_meltwater): a cell whose liquid fraction reaches 1 becomes air (s = 0,
//   H = 0); its latent heat and any excess sensible heat are booked in the ledger as drained.
//   Partially melted cells keep their water until then (it conducts and stores heat).
//
// Time stepping: explicit (forward Euler) conduction, stable for
//     dt <= (ρ c)_min h² / (2 D k_max)  = h² / (2 D α_max)
// (D = number of axes with more than one cell; α_max = k_ice/(ρ c_ice) = 1.18e-6 m²/s is the
// largest diffusivity of the two phases); the min(s_a, s_b) open area keeps partially filled
// cells within the same bound. Boundary exchange is point-implicit per cell (exact solution
// of H + dt G T(H) / V = R with the piecewise-linear T(H)), so it adds no stability limit and
// its booked heat equals what entered the cell. advance(dt) takes equal sub-steps no larger
// than time_step_fraction · the limit.
//
// Determinism: cells are updated from the previous state only; TBB runs over z-slabs and the
// ledger adds per-slab sums in slab order, so results are bitwise identical between runs and
// thread counts.
//
// Constants (SI) and sources:
//   ice density 917 kg/m³ at 0 °C                      — CRC Handbook of Chem. & Phys.; Hobbs, Ice Physics (1974)
//   latent heat of fusion 333.55 kJ/kg                  — IAPWS / CRC Handbook (6.01 kJ/mol)
//   k_ice 2.22 W/m/K at 0 °C                            — Slack (1980), Phys. Rev. B 22, 3065; Engineering ToolBox
//   c_ice 2.05 kJ/kg/K near 0 °C (2.05 at -5 °C)        — CRC Handbook; Engineering ToolBox "Ice - thermal properties"
//   c_water 4.18 kJ/kg/K, k_water 0.56 W/m/K at 0–5 °C  — IAPWS-95 / Ramires et al. (1995), J. Phys. Chem. Ref. Data 24
//   ice emissivity 0.97 (thermal IR)                     — Warren (1982), Rev. Geophys. 20; Hori et al. (2006)
//   σ = 5.670374419e-8 W/m²/K⁴                           — CODATA 2018
//   Natural-convection h for a cold (0 °C) surface in 25–35 °C air, ΔT ≈ 25 K, L ≈ 30 mm,
//   air at ~285 K (ν 1.45e-5, α 2.0e-5, k 0.025): Ra ≈ 8e4;
//     vertical faces    Churchill & Chu (1975): Nu ≈ 9.3  → h ≈ 8 W/m²/K
//     upward faces of a cold plate (stable, like the underside of a hot plate):
//                       Nu = 0.27 Ra^¼ (Incropera et al., Fundamentals of Heat and Mass
//                       Transfer, 6th ed., Eq. 9.32)  → h ≈ 4 W/m²/K
//     downward faces of a cold plate (unstable, like the top of a hot plate):
//                       Nu = 0.54 Ra^¼ (Incropera Eq. 9.30) → h ≈ 8 W/m²/K
//   Ground contact conductance: an assumed order of magnitude for ice on a damp absorbent
//   cloth/paper (a thin water film): 30 W/m²/K; a parameter to fit, not a measured value.

#include <meltlab/sim/physics/ice_fraction.h>

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <vector>

namespace meltlab::sim::physics {

namespace constants {
inline constexpr double kIceDensity = 917.0;                ///< kg/m³ at 0 °C
inline constexpr double kLatentHeat = 333.55e3;             ///< J/kg
inline constexpr double kIceConductivity = 2.22;            ///< W/m/K at 0 °C
inline constexpr double kIceHeatCapacity = 2.05e3;          ///< J/kg/K
inline constexpr double kWaterHeatCapacity = 4.18e3;        ///< J/kg/K
inline constexpr double kWaterConductivity = 0.56;          ///< W/m/K
inline constexpr double kIceEmissivity = 0.97;              ///< thermal infrared
inline constexpr double kStefanBoltzmann = 5.670374419e-8;  ///< W/m²/K⁴
inline constexpr double kZeroCelsiusK = 273.15;
}  // namespace constants

struct IceMeltParams {
  // material (defaults: the constants above)
  double density_kg_m3 = constants::kIceDensity;
  double latent_heat_J_kg = constants::kLatentHeat;
  double k_ice_W_mK = constants::kIceConductivity;
  double c_ice_J_kgK = constants::kIceHeatCapacity;
  double k_water_W_mK = constants::kWaterConductivity;
  double c_water_J_kgK = constants::kWaterHeatCapacity;
  double initial_temperature_C = -10.0;  ///< uniform initial temperature of the ice, <= 0

  // air: natural convection, by face orientation (see header comment for the values)
  double air_temperature_C = 30.0;
  double h_up_W_m2K = 4.0;        ///< upward-facing faces (n_z = +1)
  double h_vertical_W_m2K = 8.0;  ///< vertical faces (n_z = 0)
  double h_down_W_m2K = 8.0;      ///< downward-facing faces (n_z = -1)
  /// long-wave exchange with surroundings at air temperature; 0 switches it off
  double emissivity = constants::kIceEmissivity;

  // lamp (optional): absorbed flux = absorptivity · irradiance · max(0, n · direction)
  double lamp_irradiance_W_m2 = 0.0;
  double lamp_absorptivity = 0.5;
  Eigen::Vector3d lamp_direction = Eigen::Vector3d::UnitZ();  ///< towards the lamp (normalised internally)

  // ground under layer k = 0
  bool ground_contact = true;
  double ground_temperature_C = 30.0;
  double ground_conductance_W_m2K = 30.0;  ///< +infinity: Dirichlet wall at ground_temperature_C

  bool drain_meltwater = true;
  double time_step_fraction = 0.9;  ///< sub-step = fraction · stable limit, in (0, 1]
  double min_fraction = 1e-3;       ///< initial fractions below this are air
  bool parallel = true;             ///< TBB over z-slabs (results identical either way)
};

/// Energy bookkeeping since construction, joules. Heat in = Σ boundary kinds =
/// enthalpy change of the grid + drained; latent + sensible split of the same.
struct EnergyLedger {
  double convection_J = 0;
  double ambient_radiation_J = 0;
  double lamp_J = 0;
  double ground_J = 0;
  double drained_latent_J = 0;    ///< s ρ L V of cells that drained
  double drained_sensible_J = 0;  ///< heat above the melting point carried away by drained water
  double initial_enthalpy_J = 0;  ///< Σ H V at construction
  double enthalpy_J = 0;          ///< Σ H V now
  double latent_J = 0;            ///< ρ L × mass melted so far (drained and retained)
  double heat_in_J() const { return convection_J + ambient_radiation_J + lamp_J + ground_J; }
  /// Enthalpy change plus drained energy; equals heat_in_J() up to round-off.
  double stored_J() const { return enthalpy_J - initial_enthalpy_J + drained_latent_J + drained_sensible_J; }
  /// stored_J() - latent_J: sensible heat change (warming of ice and retained/drained water).
  double sensible_J() const { return stored_J() - latent_J; }
};

class EnthalpySolver {
 public:
  /// `initial_fraction`: ice volume fraction per cell in [0, 1] (e.g. voxelize_fraction).
  /// Its geometry (h, origin, size) is the solver's grid; layer k = 0 sits on the ground.
  EnthalpySolver(const Grid3<float>& initial_fraction, const IceMeltParams& params);
  /// Occupancy (0/1) as a fraction grid.
  EnthalpySolver(const Grid3<std::uint8_t>& ice_occupancy, const IceMeltParams& params);

  /// Advances by dt_s (>= 0) in equal sub-steps no larger than time_step_s().
  void advance(double dt_s);
  /// Advances until the ice mass falls to `mass_kg` or `max_time_s` is reached, one stable
  /// step at a time; returns whether the mass was reached.
  bool advance_until_mass(double mass_kg, double max_time_s);

  double time_s() const { return time_s_; }
  std::int64_t steps() const { return steps_; }
  /// Stable explicit step (see header comment) times time_step_fraction.
  double time_step_s() const { return dt_max_; }
  double stable_time_step_s() const { return dt_stable_; }

  IceFraction ice_fraction() const;
  /// H2O content s per cell (ice + retained water).
  Grid3<float> content_fraction() const;
  Grid3<float> liquid_fraction() const;  ///< f_l of the cell's content (0 where s = 0)
  Grid3<float> temperature_C() const;    ///< NaN-free: air cells report the air temperature
  const Grid3<double>& enthalpy_J_m3() const { return H_; }
  double ice_mass_kg() const;
  double ice_volume_m3() const;
  EnergyLedger ledger() const;
  const IceMeltParams& params() const { return p_; }

  /// How far the body has dropped onto the ground so far (whole cells), metres.
  double settled_m() const { return settled_m_; }
  /// Exposed surface area of the body by the diffuse face weights (for tests/diagnostics).
  double surface_area_m2() const;

 private:
  struct CellExchange;  ///< what one cell exchanges during a step (enthalpy.cpp)

  /// One explicit step: every H2O cell's exchange, its point-implicit update, the ledger.
  void step(double dt);
  CellExchange cell_exchange(int i, int j, int k) const;
  double subcell_bits(int i, int j, int k, CellExchange& x) const;
  double implicit_enthalpy(std::size_t c, const CellExchange& x, double dt) const;
  void refresh_derived();
  void settle();
  double temperature_of(double H, double s) const;

  IceMeltParams p_;
  Grid3<double> H_;  ///< J/m³ of cell
  Grid3<double> s_;  ///< content fraction
  // derived, refreshed each step
  std::vector<double> T_, k_, b_;
  std::vector<double> gx_, gy_, gz_;
  std::vector<double> H_next_;
  std::vector<double> slab_conv_, slab_rad_, slab_lamp_, slab_ground_, slab_drain_lat_, slab_drain_sens_;
  std::vector<std::uint8_t> drained_;
  double time_s_ = 0;
  std::int64_t steps_ = 0;
  double dt_stable_ = 0, dt_max_ = 0;
  double h_rad_ = 0;
  double settled_m_ = 0;
  Eigen::Vector3d lamp_dir_ = Eigen::Vector3d::UnitZ();
  EnergyLedger ledger_;
};

/// Two-phase Neumann similarity solution of the Stefan problem for melting (Carslaw & Jaeger
/// §11.2; Alexiades & Solomon, Mathematical Modeling of Melting and Freezing Processes, §2.3):
/// a half space x > 0 of ice at `ice_C` (<= 0), the wall x = 0 held at `wall_C` (> 0) from
/// t = 0; equal densities (p.density_kg_m3). The front is X(t) = 2 λ sqrt(α_l t), λ the root of
///   λ = St_l e^{-λ²} / (√π erf λ) - St_s e^{-ν²λ²} / (ν √π erfc νλ),
///   St_l = c_w (T_w - 0)/L, St_s = c_i (0 - T_i)/L, ν = sqrt(α_l/α_s)    (bisection, 1e-14).
struct NeumannStefan {
  double lambda = 0;
  double alpha_liquid_m2_s = 0, alpha_solid_m2_s = 0;
  double wall_C = 0, ice_C = 0;
  double interface_m(double t_s) const;
  /// Temperature at depth x and time t.
  double temperature_C(double x_m, double t_s) const;
};
NeumannStefan neumann_stefan(const IceMeltParams& p, double wall_C, double ice_C);

/// Parameters and grid of the 1-D Stefan problem on the solver: a column of 1 x 1 x n cells of
/// edge h filled with ice at `ice_C`, the wall at z = 0 a Dirichlet ground (G = ∞) at `wall_C`,
/// no air exchange, meltwater kept (it conducts), serial (1 cell per slab).
struct StefanSetup {
  Grid3<float> fraction;
  IceMeltParams params;
};
StefanSetup stefan_column(double h_m, double depth_m, double wall_C, double ice_C);
/// Front position of a Stefan column: h Σ f_l over the column (the melted depth).
double stefan_front_m(const EnthalpySolver& solver);

}  // namespace meltlab::sim::physics
