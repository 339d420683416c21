// sim::MeltReplay: the mesh after n cycles is the simulator's after n steps (bitwise, in
// doubles for a float run), it only runs forward, and a repeated cycle costs no step.

#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/kl_field.h>
#include <meltlab/sim/mesh_sequence.h>

#include <gtest/gtest.h>

#include <stdexcept>

namespace meltlab::sim {
namespace {

void expect_same_mesh(const TriMesh<double>& a, const TriMesh<double>& b, const std::string& what) {
  ASSERT_EQ(a.vertex_slots(), b.vertex_slots()) << what;
  EXPECT_EQ(a.vertex_alive, b.vertex_alive) << what;
  EXPECT_EQ(a.triangle_alive, b.triangle_alive) << what;
  EXPECT_EQ(a.triangle, b.triangle) << what;
  EXPECT_EQ(a.position, b.position) << what;  // bitwise
}

template <class Real>
void check_replay_follows_the_simulator(bool double_precision) {
  const IndexedMesh sphere = datasets::geodesic_sphere(8, 0.05);
  const MeltParams p = relative_melt_params(sphere, 0.05, 0.5, 1.0);
  MeltReplay replay(sphere, p, make_constant_kl(1.0), double_precision);
  MeltSimulator<Real> reference(TriMesh<Real>::from_indexed(sphere), p, make_constant_kl(1.0), Execution::kSerial);
  EXPECT_EQ(replay.cycle(), 0);
  expect_same_mesh(replay.mesh_at(0), reference.mesh().template cast<double>(), "cycle 0");
  std::int64_t at = 0;
  for (std::int64_t cycle : {1, 4, 4, 9, 30}) {
    while (at < cycle) {
      reference.step();
      ++at;
    }
    expect_same_mesh(replay.mesh_at(cycle), reference.mesh().template cast<double>(), "cycle " + std::to_string(cycle));
    EXPECT_EQ(replay.cycle(), cycle);
  }
  EXPECT_THROW(replay.mesh_at(29), std::logic_error);
}

TEST(MeltReplay, DoubleRunIsTheSimulatorsMeshCycleByCycle) { check_replay_follows_the_simulator<double>(true); }

TEST(MeltReplay, FloatRunIsTheSimulatorsMeshInDoubles) { check_replay_follows_the_simulator<float>(false); }

}  // namespace
}  // namespace meltlab::sim
