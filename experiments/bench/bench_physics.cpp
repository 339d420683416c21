// Reference melt solver (sim/physics): resolution against run time and interface error.
//   BM_NeumannStefan/h_um  — 1-D two-phase Stefan column (ice at -10 °C, wall at 25 °C, 2 h of
//                            melt), counters: h_mm, dt_s, steps, front_mm, exact_mm, rel_error.
//   BM_ShrinkingSphere/h_um — 15 mm sphere at 0 °C under a uniform 2500 W/m² flux until half
//                            its mass melted; counters: cells, rel_error (radius).
//   BM_GiraffeBlock/h_um   — the 250 g giraffe mold with the default lab parameters, 10 min of
//                            melt; counters: cells, steps, s_per_sim_hour.
// Run with --benchmark_out=FILE --benchmark_out_format=json.
#include <meltlab/datasets/molds.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/physics/enthalpy.h>
#include <meltlab/sim/physics/voxelize.h>

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

namespace {

using namespace meltlab::sim::physics;

void BM_NeumannStefan(benchmark::State& state) {
  const double h = static_cast<double>(state.range(0)) * 1e-6;
  const double wall = 25.0, ice = -10.0, t = 7200.0;
  double front = 0, exact = 0, dt = 0, steps = 0;
  for (auto _ : state) {
    auto s = stefan_column(h, 0.3, wall, ice);
    EnthalpySolver solver(s.fraction, s.params);
    solver.advance(t);
    front = stefan_front_m(solver);
    exact = neumann_stefan(s.params, wall, ice).interface_m(t);
    dt = solver.time_step_s();
    steps = static_cast<double>(solver.steps());
    benchmark::DoNotOptimize(front);
  }
  state.counters["h_mm"] = h * 1e3;
  state.counters["dt_s"] = dt;
  state.counters["steps"] = steps;
  state.counters["front_mm"] = front * 1e3;
  state.counters["exact_mm"] = exact * 1e3;
  state.counters["rel_error"] = std::abs(front - exact) / exact;
}
BENCHMARK(BM_NeumannStefan)
    ->Arg(4000)
    ->Arg(2000)
    ->Arg(1000)
    ->Arg(500)
    ->Arg(250)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

void BM_ShrinkingSphere(benchmark::State& state) {
  const double h = static_cast<double>(state.range(0)) * 1e-6, r0 = 15e-3;
  const auto mesh = meltlab::datasets::geodesic_sphere(48, r0);
  VoxelizeOptions vo;
  vo.h_m = h;
  vo.floor_at_mesh_bottom = false;
  const auto frac = voxelize_fraction(mesh, vo);
  IceMeltParams p;
  p.initial_temperature_C = 0;
  p.air_temperature_C = 25;
  p.h_up_W_m2K = p.h_vertical_W_m2K = p.h_down_W_m2K = 100;  // q = 2500 W/m²
  p.emissivity = 0;
  p.ground_contact = false;
  double err = 0;
  for (auto _ : state) {
    EnthalpySolver solver(frac, p);
    const double r0v = std::cbrt(3 * solver.ice_volume_m3() / (4 * std::numbers::pi));
    const double r_half = r0v / std::cbrt(2.0);
    solver.advance((r0v - r_half) * p.density_kg_m3 * p.latent_heat_J_kg / 2500.0);
    const double r = std::cbrt(3 * solver.ice_volume_m3() / (4 * std::numbers::pi));
    err = std::abs(r - r_half) / r_half;
  }
  state.counters["h_mm"] = h * 1e3;
  state.counters["cells"] = static_cast<double>(frac.size());
  state.counters["rel_error"] = err;
}
BENCHMARK(BM_ShrinkingSphere)->Arg(3000)->Arg(2000)->Arg(1500)->Arg(1000)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_GiraffeBlock(benchmark::State& state) {
  const double h = static_cast<double>(state.range(0)) * 1e-6;
  const auto mesh = meltlab::datasets::mold_mesh(meltlab::datasets::Mold::kGiraffe);
  VoxelizeOptions vo;
  vo.h_m = h;
  const auto frac = voxelize_fraction(mesh, vo);
  double steps = 0;
  for (auto _ : state) {
    EnthalpySolver solver(frac, IceMeltParams{});
    solver.advance(600.0);
    steps = static_cast<double>(solver.steps());
  }
  state.counters["h_mm"] = h * 1e3;
  state.counters["cells"] = static_cast<double>(frac.size());
  state.counters["steps"] = steps;
}
BENCHMARK(BM_GiraffeBlock)->Arg(4000)->Arg(3000)->Arg(2500)->Arg(2000)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
