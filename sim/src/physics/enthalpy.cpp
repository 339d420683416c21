// Enthalpy-method reference melt; the model, its stability bound and the sources of the
// constants are documented in enthalpy.h.
#include <meltlab/sim/physics/enthalpy.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace meltlab::sim::physics {
namespace {

Grid3<float> to_fraction(const Grid3<std::uint8_t>& occ) {
  Grid3<float> f(occ.nx, occ.ny, occ.nz, occ.h_m, occ.origin_m, 0.0f);
  for (std::size_t c = 0; c < occ.size(); ++c) f.value[c] = occ.value[c] ? 1.0f : 0.0f;
  return f;
}

template <class F>
void for_each_slab(int nz, bool parallel, F&& f) {
  if (parallel && nz > 1) {
    tbb::parallel_for(tbb::blocked_range<int>(0, nz), [&](const tbb::blocked_range<int>& r) {
      for (int k = r.begin(); k != r.end(); ++k) f(k);
    });
  } else {
    for (int k = 0; k < nz; ++k) f(k);
  }
}

}  // namespace

EnthalpySolver::EnthalpySolver(const Grid3<std::uint8_t>& ice_occupancy, const IceMeltParams& params)
    : EnthalpySolver(to_fraction(ice_occupancy), params) {}

EnthalpySolver::EnthalpySolver(const Grid3<float>& initial_fraction, const IceMeltParams& params) : p_(params) {
  const auto& g = initial_fraction;
  if (g.nx <= 0 || g.ny <= 0 || g.nz <= 0 || !(g.h_m > 0))
    throw std::invalid_argument("EnthalpySolver: empty grid or h <= 0");
  if (!(p_.initial_temperature_C <= 0))
    throw std::invalid_argument("EnthalpySolver: initial ice temperature must be <= 0 °C");
  if (!(p_.time_step_fraction > 0 && p_.time_step_fraction <= 1))
    throw std::invalid_argument("EnthalpySolver: time_step_fraction must be in (0, 1]");
  if (!(p_.density_kg_m3 > 0 && p_.latent_heat_J_kg > 0 && p_.k_ice_W_mK > 0 && p_.c_ice_J_kgK > 0 &&
        p_.k_water_W_mK > 0 && p_.c_water_J_kgK > 0))
    throw std::invalid_argument("EnthalpySolver: material constants must be positive");
  H_ = Grid3<double>(g.nx, g.ny, g.nz, g.h_m, g.origin_m, 0.0);
  s_ = Grid3<double>(g.nx, g.ny, g.nz, g.h_m, g.origin_m, 0.0);
  for (std::size_t c = 0; c < g.size(); ++c) {
    double f = std::clamp(static_cast<double>(g.value[c]), 0.0, 1.0);
    if (!(f >= p_.min_fraction)) f = 0.0;
    s_.value[c] = f;
    H_.value[c] = f * p_.density_kg_m3 * p_.c_ice_J_kgK * p_.initial_temperature_C;
  }
  const std::size_t n = g.size();
  T_.assign(n, 0.0);
  k_.assign(n, 0.0);
  b_.assign(n, 0.0);
  gx_.assign(n, 0.0);
  gy_.assign(n, 0.0);
  gz_.assign(n, 0.0);
  H_next_.assign(n, 0.0);
  drained_.assign(n, 0);
  const auto nzs = static_cast<std::size_t>(g.nz);
  for (auto* v : {&slab_conv_, &slab_rad_, &slab_lamp_, &slab_ground_, &slab_drain_lat_, &slab_drain_sens_})
    v->assign(nzs, 0.0);

  const int dims = (g.nx > 1) + (g.ny > 1) + (g.nz > 1);
  const double alpha_max = std::max(p_.k_ice_W_mK / (p_.density_kg_m3 * p_.c_ice_J_kgK),
                                    p_.k_water_W_mK / (p_.density_kg_m3 * p_.c_water_J_kgK));
  dt_stable_ = g.h_m * g.h_m / (2.0 * std::max(dims, 1) * alpha_max);
  dt_max_ = p_.time_step_fraction * dt_stable_;

  const double Ta = p_.air_temperature_C + constants::kZeroCelsiusK, Ts = constants::kZeroCelsiusK;
  h_rad_ = std::max(p_.emissivity, 0.0) * constants::kStefanBoltzmann * (Ta * Ta + Ts * Ts) * (Ta + Ts);
  lamp_dir_ = p_.lamp_direction.norm() > 0 ? Eigen::Vector3d(p_.lamp_direction.normalized()) : Eigen::Vector3d::UnitZ();

  double e = 0;
  for (double v : H_.value) e += v;
  ledger_.initial_enthalpy_J = e * g.h_m * g.h_m * g.h_m;
  refresh_derived();
}

double EnthalpySolver::temperature_of(double H, double s) const {
  if (!(s > 0)) return p_.air_temperature_C;
  if (H < 0) return H / (s * p_.density_kg_m3 * p_.c_ice_J_kgK);
  const double lat = s * p_.density_kg_m3 * p_.latent_heat_J_kg;
  if (H <= lat) return 0.0;
  return (H - lat) / (s * p_.density_kg_m3 * p_.c_water_J_kgK);
}

void EnthalpySolver::refresh_derived() {
  const int nx = H_.nx, ny = H_.ny, nz = H_.nz;
  const double rhoL = p_.density_kg_m3 * p_.latent_heat_J_kg;
  for_each_slab(nz, p_.parallel, [&](int k) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = H_.index(i, j, k);
        const double s = s_.value[c], H = H_.value[c];
        if (s > 0) {
          const double fl = std::clamp(H / (s * rhoL), 0.0, 1.0);
          T_[c] = temperature_of(H, s);
          k_[c] = (1.0 - fl) * p_.k_ice_W_mK + fl * p_.k_water_W_mK;
          b_[c] = p_.drain_meltwater ? s * (1.0 - fl) : s;
        } else {
          T_[c] = p_.air_temperature_C;
          k_[c] = 0;
          b_[c] = 0;
        }
      }
  });
  // Sobel gradient of b (difference along the axis, (1,2,1) smoothing across it; weights sum
  // to 16 per side, so g = Σ / (32 h)); outside the grid mirrors the border cell (insulated
  // sides). Only needed at body cells and their face neighbours.
  const double inv32h = 1.0 / (32.0 * H_.h_m);
  for_each_slab(nz, p_.parallel, [&](int k) {
    auto bv = [&](int a, int bb, int cc) {
      return b_[H_.index(std::clamp(a, 0, nx - 1), std::clamp(bb, 0, ny - 1), std::clamp(cc, 0, nz - 1))];
    };
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = H_.index(i, j, k);
        const bool near = b_[c] > 0 || bv(i - 1, j, k) > 0 || bv(i + 1, j, k) > 0 || bv(i, j - 1, k) > 0 ||
                          bv(i, j + 1, k) > 0 || bv(i, j, k - 1) > 0 || bv(i, j, k + 1) > 0;
        if (!near) {
          gx_[c] = gy_[c] = gz_[c] = 0;
          continue;
        }
        double sx = 0, sy = 0, sz = 0;
        for (int u = -1; u <= 1; ++u)
          for (int v = -1; v <= 1; ++v) {
            const double w = (2 - std::abs(u)) * (2 - std::abs(v));
            sx += w * (bv(i + 1, j + u, k + v) - bv(i - 1, j + u, k + v));
            sy += w * (bv(i + u, j + 1, k + v) - bv(i + u, j - 1, k + v));
            sz += w * (bv(i + u, j + v, k + 1) - bv(i + u, j + v, k - 1));
          }
        gx_[c] = sx * inv32h;
        gy_[c] = sy * inv32h;
        gz_[c] = sz * inv32h;
      }
  });
}

namespace {
constexpr int kDir[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
}

// The heat exchange of one H2O cell during a step (the model in enthalpy.h): conduction from
// its H2O neighbours, and the conductances and lamp power of its exposed faces and of the ground.
struct EnthalpySolver::CellExchange {
  double q_cond = 0;  ///< conduction from the neighbours, W
  double G_air = 0;   ///< convection conductance of the exposed faces, W/K
  double G_rad = 0;   ///< linearised ambient radiation conductance, W/K
  double P_lamp = 0;  ///< absorbed lamp power, W
  double G_gr = 0;    ///< ground contact conductance, W/K
};

// Sub-cell bits (see header) of cell (i, j, k) with 0 < b < 1: a sheet on the ground gets the
// missing part of its top face (added to x), an isolated chunk elsewhere the area of a compact
// chunk. Returns the chunk's area factor for the faces (1 for anything else).
double EnthalpySolver::subcell_bits(int i, int j, int k, CellExchange& x) const {
  const double bc = b_[H_.index(i, j, k)];
  if (!(bc < 1.0 && bc > 0)) return 1.0;
  if (k == 0 && p_.ground_contact) {
    const double b_above = H_.nz > 1 ? b_[H_.index(i, j, 1)] : 0.0;
    if (b_above < bc) {
      const double A0 = H_.h_m * H_.h_m;
      const double lamp = p_.lamp_absorptivity * p_.lamp_irradiance_W_m2;
      const double A_up = A0 * (1.0 - bc) * (bc - b_above) / bc;
      x.G_air += p_.h_up_W_m2K * A_up;
      x.G_rad += h_rad_ * A_up;
      if (lamp > 0) x.P_lamp += lamp * std::max(0.0, lamp_dir_.z()) * A_up;
    }
    return 1.0;
  }
  for (int d = 0; d < 6; ++d) {
    const int ii = i + kDir[d][0], jj = j + kDir[d][1], kk = k + kDir[d][2];
    if (H_.inside(ii, jj, kk) && b_[H_.index(ii, jj, kk)] > bc) return 1.0;  // not a peak
  }
  return 1.0 / std::cbrt(bc);
}

EnthalpySolver::CellExchange EnthalpySolver::cell_exchange(int i, int j, int k) const {
  const double h = H_.h_m, A0 = h * h;
  const bool dirichlet = std::isinf(p_.ground_conductance_W_m2K);
  const double inv_G = dirichlet ? 0.0 : 1.0 / p_.ground_conductance_W_m2K;
  const double lamp = p_.lamp_absorptivity * p_.lamp_irradiance_W_m2;
  const std::size_t c = H_.index(i, j, k);
  const double sc = s_.value[c], Tc = T_[c], kc = k_[c], bc = b_[c];
  CellExchange x;
  const double chunk = subcell_bits(i, j, k, x);
  for (int d = 0; d < 6; ++d) {
    const int ii = i + kDir[d][0], jj = j + kDir[d][1], kk = k + kDir[d][2];
    if (!H_.inside(ii, jj, kk)) {
      if (d == 4 && p_.ground_contact) {
        const double area = A0 * sc;  // footprint of the cell's ice and retained water
        x.G_gr += area / (inv_G + 0.5 * h / kc);
      }
      continue;  // other grid faces: insulated
    }
    // Conduction through the face (two half cells in series, the smaller content open).
    const std::size_t n = H_.index(ii, jj, kk);
    const double sn = s_.value[n];
    if (sn > 0) {
      const double kn = k_[n];
      const double K = std::min(sc, sn) * h * (2.0 * (kc * kn) / (kc + kn));
      x.q_cond += K * (T_[n] - Tc);
    }
    // The exposed area of the face: |Δb|, weighted by the smoothed normal's component.
    const double bn = b_[n];
    if (bn == bc) continue;
    // the face's heat goes to the outer (lower b) cell if it holds H2O, else to the inner one
    const bool receive = bn > bc || !(sn > 0);
    if (!receive) continue;
    const int axis = d / 2;
    const double sign = (d % 2) ? 1.0 : -1.0;  // +1: neighbour on the + side
    Eigen::Vector3d g(gx_[c] + gx_[n], gy_[c] + gy_[n], gz_[c] + gz_[n]);
    if (!(g[axis] * sign * (bn - bc) > 0)) g[axis] = sign * (bn - bc) / h;  // smoothed normal disagrees with the jump
    const double gn = g.norm();
    if (!(gn > 0)) continue;
    const double area = chunk * A0 * std::abs(bn - bc) * std::abs(g[axis]) / gn;
    const Eigen::Vector3d nout = -g / gn;
    const double nz_ = nout.z();
    const double hc = p_.h_vertical_W_m2K * (1.0 - std::abs(nz_)) + p_.h_up_W_m2K * std::max(nz_, 0.0) +
                      p_.h_down_W_m2K * std::max(-nz_, 0.0);
    x.G_air += hc * area;
    x.G_rad += h_rad_ * area;
    if (lamp > 0) x.P_lamp += lamp * std::max(0.0, nout.dot(lamp_dir_)) * area;
  }
  return x;
}

// Point-implicit boundary exchange of cell c: the exact solution of H + dt G T(H) / V = R,
// T piecewise linear in H (solid, mushy, liquid).
double EnthalpySolver::implicit_enthalpy(std::size_t c, const CellExchange& x, double dt) const {
  const double h = H_.h_m, V = h * h * h;
  const double rho = p_.density_kg_m3, rhoL = rho * p_.latent_heat_J_kg;
  const double Ta = p_.air_temperature_C, Tg = p_.ground_temperature_C;
  const double sc = s_.value[c];
  const double Gt = x.G_air + x.G_rad + x.G_gr;
  const double R = H_.value[c] + dt / V * (x.q_cond + x.P_lamp + (x.G_air + x.G_rad) * Ta + x.G_gr * Tg);
  const double a = dt * Gt / V;
  const double lat = sc * rhoL;
  if (R < 0) return R / (1.0 + a / (sc * rho * p_.c_ice_J_kgK));
  if (R <= lat) return R;
  return lat + (R - lat) / (1.0 + a / (sc * rho * p_.c_water_J_kgK));
}

void EnthalpySolver::step(double dt) {
  const int nx = H_.nx, ny = H_.ny, nz = H_.nz;
  const double h = H_.h_m, V = h * h * h;
  const double rhoL = p_.density_kg_m3 * p_.latent_heat_J_kg;
  const double Ta = p_.air_temperature_C, Tg = p_.ground_temperature_C;

  // Every H2O cell from the previous state; the energy booked per z-slab.
  for_each_slab(nz, p_.parallel, [&](int k) {
    double conv = 0, rad = 0, lmp = 0, gr = 0, dlat = 0, dsens = 0;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = H_.index(i, j, k);
        drained_[c] = 0;
        const double sc = s_.value[c];
        if (!(sc > 0)) {
          H_next_[c] = 0;
          continue;
        }
        const CellExchange x = cell_exchange(i, j, k);
        double Hn = implicit_enthalpy(c, x, dt);
        const double Tn = temperature_of(Hn, sc);
        conv += dt * x.G_air * (Ta - Tn);
        rad += dt * x.G_rad * (Ta - Tn);
        lmp += dt * x.P_lamp;
        gr += dt * x.G_gr * (Tg - Tn);
        const double lat = sc * rhoL;
        if (p_.drain_meltwater && Hn >= lat) {
          dlat += lat * V;
          dsens += (Hn - lat) * V;
          drained_[c] = 1;
          Hn = 0;
        }
        H_next_[c] = Hn;
      }
    slab_conv_[static_cast<std::size_t>(k)] = conv;
    slab_rad_[static_cast<std::size_t>(k)] = rad;
    slab_lamp_[static_cast<std::size_t>(k)] = lmp;
    slab_ground_[static_cast<std::size_t>(k)] = gr;
    slab_drain_lat_[static_cast<std::size_t>(k)] = dlat;
    slab_drain_sens_[static_cast<std::size_t>(k)] = dsens;
  });
  // The ledger in slab order (deterministic whatever the threads), then the new state.
  for (std::size_t k = 0; k < static_cast<std::size_t>(nz); ++k) {
    ledger_.convection_J += slab_conv_[k];
    ledger_.ambient_radiation_J += slab_rad_[k];
    ledger_.lamp_J += slab_lamp_[k];
    ledger_.ground_J += slab_ground_[k];
    ledger_.drained_latent_J += slab_drain_lat_[k];
    ledger_.drained_sensible_J += slab_drain_sens_[k];
  }
  H_.value.swap(H_next_);
  for (std::size_t c = 0; c < H_.size(); ++c)
    if (drained_[c]) s_.value[c] = 0;
  if (p_.ground_contact) settle();
  time_s_ += dt;
  ++steps_;
  refresh_derived();
}

void EnthalpySolver::settle() {
  // the body rests on the ground: while layer 0 is empty and some layer above is not, the
  // whole body drops by one cell (a rigid drop; no energy changes hands)
  const std::size_t layer = static_cast<std::size_t>(H_.nx) * static_cast<std::size_t>(H_.ny);
  auto layer_empty = [&](int k) {
    for (std::size_t c = layer * static_cast<std::size_t>(k); c < layer * static_cast<std::size_t>(k + 1); ++c)
      if (s_.value[c] > 0) return false;
    return true;
  };
  int first = 0;
  while (first < H_.nz && layer_empty(first)) ++first;
  if (first == 0 || first == H_.nz) return;
  const std::size_t shift = layer * static_cast<std::size_t>(first);
  std::move(H_.value.begin() + static_cast<std::ptrdiff_t>(shift), H_.value.end(), H_.value.begin());
  std::move(s_.value.begin() + static_cast<std::ptrdiff_t>(shift), s_.value.end(), s_.value.begin());
  std::fill(H_.value.end() - static_cast<std::ptrdiff_t>(shift), H_.value.end(), 0.0);
  std::fill(s_.value.end() - static_cast<std::ptrdiff_t>(shift), s_.value.end(), 0.0);
  settled_m_ += first * H_.h_m;
}

void EnthalpySolver::advance(double dt_s) {
  if (!(dt_s >= 0)) throw std::invalid_argument("EnthalpySolver::advance: dt must be >= 0");
  if (dt_s == 0) return;
  const auto n = static_cast<std::int64_t>(std::ceil(dt_s / dt_max_ * (1.0 - 1e-12)));
  const std::int64_t steps = std::max<std::int64_t>(n, 1);
  const double sub = dt_s / static_cast<double>(steps);
  for (std::int64_t s = 0; s < steps; ++s) step(sub);
}

bool EnthalpySolver::advance_until_mass(double mass_kg, double max_time_s) {
  while (ice_mass_kg() > mass_kg) {
    if (time_s_ >= max_time_s) return false;
    step(std::min(dt_max_, std::max(max_time_s - time_s_, 1e-12)));
  }
  return true;
}

IceFraction EnthalpySolver::ice_fraction() const {
  IceFraction f(H_.nx, H_.ny, H_.nz, H_.h_m, H_.origin_m, 0.0f);
  const double rhoL = p_.density_kg_m3 * p_.latent_heat_J_kg;
  for (std::size_t c = 0; c < f.size(); ++c) {
    const double s = s_.value[c];
    if (s > 0) f.value[c] = static_cast<float>(s * (1.0 - std::clamp(H_.value[c] / (s * rhoL), 0.0, 1.0)));
  }
  return f;
}

Grid3<float> EnthalpySolver::content_fraction() const {
  Grid3<float> f(H_.nx, H_.ny, H_.nz, H_.h_m, H_.origin_m, 0.0f);
  for (std::size_t c = 0; c < f.size(); ++c) f.value[c] = static_cast<float>(s_.value[c]);
  return f;
}

Grid3<float> EnthalpySolver::liquid_fraction() const {
  Grid3<float> f(H_.nx, H_.ny, H_.nz, H_.h_m, H_.origin_m, 0.0f);
  const double rhoL = p_.density_kg_m3 * p_.latent_heat_J_kg;
  for (std::size_t c = 0; c < f.size(); ++c) {
    const double s = s_.value[c];
    if (s > 0) f.value[c] = static_cast<float>(std::clamp(H_.value[c] / (s * rhoL), 0.0, 1.0));
  }
  return f;
}

Grid3<float> EnthalpySolver::temperature_C() const {
  Grid3<float> f(H_.nx, H_.ny, H_.nz, H_.h_m, H_.origin_m, 0.0f);
  for (std::size_t c = 0; c < f.size(); ++c) f.value[c] = static_cast<float>(T_[c]);
  return f;
}

double EnthalpySolver::ice_volume_m3() const {
  const double rhoL = p_.density_kg_m3 * p_.latent_heat_J_kg;
  double v = 0;
  for (std::size_t c = 0; c < H_.size(); ++c) {
    const double s = s_.value[c];
    if (s > 0) v += s * (1.0 - std::clamp(H_.value[c] / (s * rhoL), 0.0, 1.0));
  }
  return v * H_.h_m * H_.h_m * H_.h_m;
}

double EnthalpySolver::ice_mass_kg() const { return ice_volume_m3() * p_.density_kg_m3; }

EnergyLedger EnthalpySolver::ledger() const {
  EnergyLedger l = ledger_;
  const double V = H_.h_m * H_.h_m * H_.h_m, rhoL = p_.density_kg_m3 * p_.latent_heat_J_kg;
  double e = 0, lat = 0;
  for (std::size_t c = 0; c < H_.size(); ++c) {
    e += H_.value[c];
    if (s_.value[c] > 0) lat += std::clamp(H_.value[c], 0.0, s_.value[c] * rhoL);
  }
  l.enthalpy_J = e * V;
  l.latent_J = lat * V + l.drained_latent_J;
  return l;
}

double EnthalpySolver::surface_area_m2() const {
  const int nx = H_.nx, ny = H_.ny, nz = H_.nz;
  const double h = H_.h_m;
  double total = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = H_.index(i, j, k);
        // each face counted once: from the cell on its - side
        for (int d = 1; d < 6; d += 2) {
          const int ii = i + kDir[d][0], jj = j + kDir[d][1], kk = k + kDir[d][2];
          if (!H_.inside(ii, jj, kk)) continue;
          const std::size_t n = H_.index(ii, jj, kk);
          if (b_[n] == b_[c]) continue;
          const int axis = d / 2;
          Eigen::Vector3d g(gx_[c] + gx_[n], gy_[c] + gy_[n], gz_[c] + gz_[n]);
          if (!(g[axis] * (b_[n] - b_[c]) > 0)) g[axis] = (b_[n] - b_[c]) / h;
          const double gn = g.norm();
          if (gn > 0) total += h * h * std::abs(b_[n] - b_[c]) * std::abs(g[axis]) / gn;
        }
      }
  return total;
}

}  // namespace meltlab::sim::physics

namespace meltlab::sim::physics {

NeumannStefan neumann_stefan(const IceMeltParams& p, double wall_C, double ice_C) {
  if (!(wall_C > 0) || !(ice_C <= 0)) throw std::invalid_argument("neumann_stefan: need wall > 0 °C >= ice");
  NeumannStefan n;
  n.wall_C = wall_C;
  n.ice_C = ice_C;
  n.alpha_liquid_m2_s = p.k_water_W_mK / (p.density_kg_m3 * p.c_water_J_kgK);
  n.alpha_solid_m2_s = p.k_ice_W_mK / (p.density_kg_m3 * p.c_ice_J_kgK);
  const double St_l = p.c_water_J_kgK * wall_C / p.latent_heat_J_kg;
  const double St_s = p.c_ice_J_kgK * (0.0 - ice_C) / p.latent_heat_J_kg;
  const double nu = std::sqrt(n.alpha_liquid_m2_s / n.alpha_solid_m2_s);
  const double sqpi = std::sqrt(std::numbers::pi);
  // f increasing in λ: f(0+) = -∞, f(large) > 0
  auto f = [&](double l) {
    return l - St_l * std::exp(-l * l) / (sqpi * std::erf(l)) +
           St_s * std::exp(-nu * nu * l * l) / (nu * sqpi * std::erfc(nu * l));
  };
  double lo = 1e-12, hi = 1.0;
  while (f(hi) < 0) hi *= 2;
  for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < 0 ? lo : hi) = mid;
  }
  n.lambda = 0.5 * (lo + hi);
  return n;
}

double NeumannStefan::interface_m(double t_s) const { return 2.0 * lambda * std::sqrt(alpha_liquid_m2_s * t_s); }

double NeumannStefan::temperature_C(double x_m, double t_s) const {
  const double X = interface_m(t_s);
  if (x_m <= X) return wall_C - wall_C * std::erf(x_m / (2.0 * std::sqrt(alpha_liquid_m2_s * t_s))) / std::erf(lambda);
  const double nu = std::sqrt(alpha_liquid_m2_s / alpha_solid_m2_s);
  return ice_C + (0.0 - ice_C) * std::erfc(x_m / (2.0 * std::sqrt(alpha_solid_m2_s * t_s))) / std::erfc(nu * lambda);
}

StefanSetup stefan_column(double h_m, double depth_m, double wall_C, double ice_C) {
  StefanSetup s;
  const int n = std::max(2, static_cast<int>(std::lround(depth_m / h_m)));
  s.fraction = Grid3<float>(1, 1, n, h_m, Eigen::Vector3d::Zero(), 1.0f);
  auto& p = s.params;
  p.initial_temperature_C = ice_C;
  p.air_temperature_C = wall_C;
  p.h_up_W_m2K = p.h_vertical_W_m2K = p.h_down_W_m2K = 0;
  p.emissivity = 0;
  p.lamp_irradiance_W_m2 = 0;
  p.ground_contact = true;
  p.ground_temperature_C = wall_C;
  p.ground_conductance_W_m2K = std::numeric_limits<double>::infinity();
  p.drain_meltwater = false;
  p.parallel = false;
  return s;
}

double stefan_front_m(const EnthalpySolver& solver) {
  const auto fl = solver.liquid_fraction();
  double x = 0;
  for (float v : fl.value) x += static_cast<double>(v);
  return x * fl.h_m;
}

}  // namespace meltlab::sim::physics
