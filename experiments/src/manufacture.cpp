#include <meltlab/core/run_folder.h>
#include <meltlab/core/hash.h>
#include <meltlab/experiments/manufacture.h>
#include <meltlab/experiments/render_json.h>
#include <meltlab/experiments/sequence_manifest.h>
#include <meltlab/experiments/simulate_run.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/render/raster/silhouette.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/mesh_io.h>
#include <meltlab/sim/physics/isosurface.h>
#include <meltlab/sim/physics/voxelize.h>
#include <meltlab/sim/quality.h>
#include <meltlab/verify/metrics.h>
#include <meltlab/verify/observations.h>
#include <meltlab/experiments/provenance.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <sstream>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

double signed_volume(const sim::IndexedMesh& m) {
  double v = 0;
  for (const auto& t : m.F) v += m.V[t[0]].dot(m.V[t[1]].cross(m.V[t[2]])) / 6.0;
  return v;
}

}  // namespace

void manufacture_sequence(const ManufactureOptions& o,
                          const std::function<void(const ManufactureProgress&)>& progress) {
  require(o.photos >= 1 && o.photos <= 100000, fmt::format("--photos: must be in [1, 100000] (got {})", o.photos));
  require(std::isfinite(o.interval_s) && o.interval_s > 0, "--interval-s: must be > 0");
  require(std::isfinite(o.mass_g) && o.mass_g > 0, "--mass-g: must be > 0");
  require(std::isfinite(o.voxel_mm) && o.voxel_mm >= 0.2 && o.voxel_mm <= 20, "--voxel-mm: must be in [0.2, 20]");
  require(o.width >= 16 && o.height >= 16 && o.width <= 8192 && o.height <= 8192,
          "--width/--height: must be in [16, 8192]");
  require(std::isfinite(o.camera_height_m) && o.camera_height_m > 0.05, "--camera-height-m: must be > 0.05");
  require(std::isfinite(o.fill) && o.fill > 0 && o.fill <= 1, "--fill: must be in (0, 1]");
  require(o.jpeg_quality >= 1 && o.jpeg_quality <= 100, "--jpeg-quality: must be in [1, 100]");
  RunFolder folder(o.out_dir, {"--out", "manifest.yaml", "sequence", o.overwrite});
  Provenance provenance = start_provenance("manufacture", o.command_line);
  const fs::path& dir = folder.path();

  // ---- the object: scaled to the ice mass, standing on the ground, centred ----
  const fs::path mesh_path = resolve_mesh_argument(o.mesh);
  sim::IndexedMesh mesh = sim::load_mesh(mesh_path).mesh;
  const double volume0 = signed_volume(mesh);
  require(volume0 > 0, fmt::format("{}: the mesh encloses no volume (inside out?)", mesh_path.string()));
  const double target_volume = o.mass_g / 1000.0 / o.physics.density_kg_m3;
  const double scale = std::cbrt(target_volume / volume0);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (auto& v : mesh.V) {
    v *= scale;
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Eigen::Vector3d shift(-(lo.x() + hi.x()) / 2, -(lo.y() + hi.y()) / 2, -lo.z());
  for (auto& v : mesh.V) v += shift;
  const Eigen::Vector2d extent = (hi - lo).head<2>();

  sim::physics::VoxelizeOptions vo;
  vo.h_m = o.voxel_mm / 1000.0;
  vo.margin_cells = 3;
  vo.floor_at_mesh_bottom = true;
  const Grid3<float> fraction0 = sim::physics::voxelize_fraction(mesh, vo);
  sim::physics::EnthalpySolver solver(fraction0, o.physics);

  // ---- camera: straight down from camera_height_m, object spanning `fill` of the image ----
  const double fx = o.fill * std::min(o.width / extent.x(), o.height / extent.y()) * o.camera_height_m;
  const render::Pinhole camera =
      render::Pinhole::look_at(o.width, o.height, fx, Eigen::Vector3d(0, 0, o.camera_height_m),
                               Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 1, 0));

  create_output_directories(dir / "frames", "--out");
  create_output_directories(dir / "truth" / "masks", "--out");
  if (o.mesh_every > 0) create_output_directories(dir / "truth" / "meshes", "--out");
  sim::save_mesh(mesh, dir / "truth" / "initial_mesh.ply");

  const verify::SegmentationSettings defaults;
  // The static ground (no ice), and renderers of the surface's coverage and true outline.
  sim::physics::IceFraction no_ice = fraction0;
  std::fill(no_ice.value.begin(), no_ice.value.end(), 0.0F);
  render::IcePhotoOptions ground_options = o.photo;
  ground_options.ground_seed = o.seed;
  const cv::Mat ground_radiance = render::render_ice_radiance(no_ice, camera, ground_options);
  render::SilhouetteRenderer coverage_renderer(camera, render::SilhouetteOptions{4, false});
  render::SilhouetteRenderer truth_renderer(camera, render::SilhouetteOptions{1, false});
  std::ostringstream mass_csv;
  std::vector<std::string> images;
  mass_csv << "time_s,mass_g\n";
  json frames = json::array();
  const double mass0_g = solver.ice_mass_kg() * 1000.0;
  for (int k = 0; k < o.photos; ++k) {
    const double t = k * o.interval_s;
    if (t > solver.time_s()) solver.advance(t - solver.time_s());
    const sim::physics::IceFraction ice = solver.ice_fraction();
    render::IcePhotoOptions po = o.photo;
    po.seed = o.seed * 1000003u + static_cast<std::uint64_t>(k);
    po.ground_seed = o.seed;
    // The ice surface is the ½ level of the solid fraction. Rays that graze a wall run
    // through the interpolated fraction below ½ for the whole height of the block and would
    // scatter visibly outside it, so the outline is taken from the surface mesh itself: the
    // volume rendering (thin ice lets the ground through) inside its anti-aliased coverage,
    // the bare ground outside. (The ice's cast shadow outside its outline is not rendered.)
    const sim::IndexedMesh surface = sim::physics::isosurface(ice);
    const auto surface_mesh = sim::TriMesh<double>::from_indexed(surface);
    cv::Mat coverage, truth;
    if (surface.F.empty()) {
      coverage = cv::Mat::zeros(o.height, o.width, CV_32FC1);
      truth = cv::Mat::zeros(o.height, o.width, CV_8UC1);
    } else {
      coverage_renderer.render(surface_mesh, coverage);
      truth_renderer.render(surface_mesh, truth);
    }
    const cv::Mat covered = coverage > 0.0F;
    cv::Mat radiance = render::render_ice_radiance(ice, camera, po, covered);
    for (int y = 0; y < radiance.rows; ++y) {
      auto* r = radiance.ptr<cv::Vec3f>(y);
      const auto* g = ground_radiance.ptr<cv::Vec3f>(y);
      const float* c = coverage.ptr<float>(y);
      for (int x = 0; x < radiance.cols; ++x) r[x] = c[x] * r[x] + (1.0F - c[x]) * g[x];
    }
    const cv::Mat photo = render::develop_photo(radiance, po);
    const std::string name = fmt::format("frame_{:04d}.jpg", k + 1);
    render::write_jpeg(dir / "frames" / name, photo, o.jpeg_quality);
    verify::write_image(dir / "truth" / "masks" / fmt::format("frame_{:04d}.png", k + 1), truth);
    // How well the verification loop's default segmentation recovers the true outline (of
    // the JPEG as written, so compression is included).
    const cv::Mat decoded = verify::read_image(dir / "frames" / name);
    const verify::Segmentation seg = verify::segment_image(decoded, defaults);
    const double true_area = cv::countNonZero(truth);
    const double p = true_area > 0 || seg.area_px > 0 ? verify::compare_masks(truth, seg.mask).P : 0.0;
    const double mass_g = solver.ice_mass_kg() * 1000.0;
    frames.push_back({{"frame", k + 1},
                      {"image", "frames/" + name},
                      {"time_s", t},
                      {"mass_g", mass_g},
                      {"volume_m3", solver.ice_volume_m3()},
                      {"true_area_px", true_area},
                      {"segmented_area_px", seg.area_px},
                      {"segmentation_P", p}});
    mass_csv << fmt::format("{},{:.6f}\n", t, mass_g);
    images.push_back("frames/" + name);
    if (o.mesh_every > 0 && k % o.mesh_every == 0 && !surface.F.empty())
      sim::save_mesh(surface, dir / "truth" / "meshes" / fmt::format("frame_{:04d}.ply", k + 1));
    if (progress) progress({k + 1, o.photos, t, mass_g});
  }

  write_text_atomically(dir / "mass.csv", mass_csv.str());
  const auto ledger = solver.ledger();
  json truth;
  truth["generator"] = "meltlab manufacture (enthalpy reference solver + photo renderer)";
  truth["mesh"] = {{"source", mesh_path.string()},
                   {"source_hash", file_hash(mesh_path)},
                   {"scale", scale},
                   {"shift_m", {shift.x(), shift.y(), shift.z()}},
                   {"initial_mesh", "truth/initial_mesh.ply"}};
  truth["physics"] = {{"voxel_mm", o.voxel_mm},
                      {"grid", {fraction0.nx, fraction0.ny, fraction0.nz}},
                      {"initial_mass_g", mass0_g},
                      {"air_C", o.physics.air_temperature_C},
                      {"ice_C", o.physics.initial_temperature_C},
                      {"ground_C", o.physics.ground_temperature_C},
                      {"h_up_W_m2K", o.physics.h_up_W_m2K},
                      {"h_vertical_W_m2K", o.physics.h_vertical_W_m2K},
                      {"h_down_W_m2K", o.physics.h_down_W_m2K},
                      {"lamp_W_m2", o.physics.lamp_irradiance_W_m2},
                      {"ground_conductance_W_m2K", o.physics.ground_conductance_W_m2K},
                      {"time_step_s", solver.time_step_s()}};
  truth["energy"] = {
      {"heat_in_J", ledger.heat_in_J()}, {"latent_J", ledger.latent_J}, {"sensible_J", ledger.sensible_J()}};
  truth["camera"] = camera_json(camera);
  truth["photo"] = {{"extinction_per_m", o.photo.extinction_per_m},
                    {"albedo", o.photo.albedo},
                    {"noise_sigma", o.photo.noise_sigma},
                    {"blur_sigma_px", o.photo.lens_blur_sigma_px},
                    {"jpeg_quality", o.jpeg_quality},
                    {"seed", o.seed}};
  truth["interval_s"] = o.interval_s;
  truth["frames"] = frames;
  truth["provenance"] = finish_provenance(provenance);
  write_text_atomically(dir / "truth" / "truth.json", truth.dump(2) + "\n");

  SequenceManifest manifest;
  manifest.comment = "Made by meltlab manufacture (physically based reference melt). Truth: truth/truth.json";
  manifest.object = fs::path(o.mesh).stem().string();
  manifest.interval_s = o.interval_s;
  manifest.camera = camera;
  manifest.ground_truth = "truth/truth.json";
  manifest.mass_series = "mass.csv";
  manifest.images = images;
  write_sequence_manifest(dir, manifest);
  folder.commit();
}

}  // namespace meltlab::experiments
