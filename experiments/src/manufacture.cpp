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

void check_options(const ManufactureOptions& o) {
  require(o.photos >= 1 && o.photos <= 100000, fmt::format("--photos: must be in [1, 100000] (got {})", o.photos));
  require(std::isfinite(o.interval_s) && o.interval_s > 0, "--interval-s: must be > 0");
  require(std::isfinite(o.mass_g) && o.mass_g > 0, "--mass-g: must be > 0");
  require(std::isfinite(o.voxel_mm) && o.voxel_mm >= 0.2 && o.voxel_mm <= 20, "--voxel-mm: must be in [0.2, 20]");
  require(o.width >= 16 && o.height >= 16 && o.width <= 8192 && o.height <= 8192,
          "--width/--height: must be in [16, 8192]");
  require(std::isfinite(o.camera_height_m) && o.camera_height_m > 0.05, "--camera-height-m: must be > 0.05");
  require(std::isfinite(o.fill) && o.fill > 0 && o.fill <= 1, "--fill: must be in (0, 1]");
  require(o.jpeg_quality >= 1 && o.jpeg_quality <= 100, "--jpeg-quality: must be in [1, 100]");
}

// The object: the mesh scaled to the ice mass, standing on the ground, centred.
struct PlacedObject {
  fs::path mesh_path;
  sim::IndexedMesh mesh;
  double scale = 1;
  Eigen::Vector3d shift;
  Eigen::Vector2d extent;  ///< of its footprint, metres
};

PlacedObject place_object(const ManufactureOptions& o) {
  PlacedObject b;
  b.mesh_path = resolve_mesh_argument(o.mesh);
  b.mesh = sim::load_mesh(b.mesh_path).mesh;
  const double volume0 = signed_volume(b.mesh);
  require(volume0 > 0, fmt::format("{}: the mesh encloses no volume (inside out?)", b.mesh_path.string()));
  const double target_volume = o.mass_g / 1000.0 / o.physics.density_kg_m3;
  b.scale = std::cbrt(target_volume / volume0);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (auto& v : b.mesh.V) {
    v *= b.scale;
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  b.shift = Eigen::Vector3d(-(lo.x() + hi.x()) / 2, -(lo.y() + hi.y()) / 2, -lo.z());
  for (auto& v : b.mesh.V) v += b.shift;
  b.extent = (hi - lo).head<2>();
  return b;
}

// The camera: straight down from camera_height_m, the object spanning `fill` of the image.
render::Pinhole overhead_camera(const ManufactureOptions& o, const Eigen::Vector2d& extent) {
  const double fx = o.fill * std::min(o.width / extent.x(), o.height / extent.y()) * o.camera_height_m;
  return render::Pinhole::look_at(o.width, o.height, fx, Eigen::Vector3d(0, 0, o.camera_height_m),
                                  Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 1, 0));
}

// One photo of the ice and its true outline.
struct Photo {
  cv::Mat image;             ///< 8-bit BGR, developed (blur, noise)
  cv::Mat truth;             ///< 8-bit mask of the ice surface's silhouette
  sim::IndexedMesh surface;  ///< the ice surface (½ level of the solid fraction)
};

// Takes the photos: the static ground (no ice) once, then per photo the volume rendering of
// the ice inside the anti-aliased coverage of its surface mesh.
class Photographer {
 public:
  Photographer(const render::Pinhole& camera, const sim::physics::IceFraction& grid, const ManufactureOptions& o)
      : camera_(camera),
        coverage_renderer_(camera, render::SilhouetteOptions{4, false}),
        truth_renderer_(camera, render::SilhouetteOptions{1, false}) {
    sim::physics::IceFraction no_ice = grid;
    std::fill(no_ice.value.begin(), no_ice.value.end(), 0.0F);
    render::IcePhotoOptions ground_options = o.photo;
    ground_options.ground_seed = o.seed;
    ground_radiance_ = render::render_ice_radiance(no_ice, camera, ground_options);
  }

  // The ice surface is the ½ level of the solid fraction. Rays that graze a wall run through
  // the interpolated fraction below ½ for the whole height of the block and would scatter
  // visibly outside it, so the outline is taken from the surface mesh itself: the volume
  // rendering (thin ice lets the ground through) inside its anti-aliased coverage, the bare
  // ground outside. (The ice's cast shadow outside its outline is not rendered.)
  Photo take(const sim::physics::IceFraction& ice, const render::IcePhotoOptions& po, int width, int height) {
    Photo photo;
    photo.surface = sim::physics::isosurface(ice);
    const auto surface_mesh = sim::TriMesh<double>::from_indexed(photo.surface);
    cv::Mat coverage;
    if (photo.surface.F.empty()) {
      coverage = cv::Mat::zeros(height, width, CV_32FC1);
      photo.truth = cv::Mat::zeros(height, width, CV_8UC1);
    } else {
      coverage_renderer_.render(surface_mesh, coverage);
      truth_renderer_.render(surface_mesh, photo.truth);
    }
    const cv::Mat covered = coverage > 0.0F;
    cv::Mat radiance = render::render_ice_radiance(ice, camera_, po, covered);
    for (int y = 0; y < radiance.rows; ++y) {
      auto* r = radiance.ptr<cv::Vec3f>(y);
      const auto* g = ground_radiance_.ptr<cv::Vec3f>(y);
      const float* c = coverage.ptr<float>(y);
      for (int x = 0; x < radiance.cols; ++x) r[x] = c[x] * r[x] + (1.0F - c[x]) * g[x];
    }
    photo.image = render::develop_photo(radiance, po);
    return photo;
  }

 private:
  render::Pinhole camera_;
  render::SilhouetteRenderer coverage_renderer_, truth_renderer_;
  cv::Mat ground_radiance_;
};

// truth/truth.json without its frames and provenance.
json truth_json(const ManufactureOptions& o, const PlacedObject& object, const Grid3<float>& fraction0, double mass0_g,
                const sim::physics::EnthalpySolver& solver, const render::Pinhole& camera) {
  const auto ledger = solver.ledger();
  json truth;
  truth["generator"] = "meltlab manufacture (enthalpy reference solver + photo renderer)";
  truth["mesh"] = {{"source", object.mesh_path.string()},
                   {"source_hash", file_hash(object.mesh_path)},
                   {"scale", object.scale},
                   {"shift_m", {object.shift.x(), object.shift.y(), object.shift.z()}},
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
  return truth;
}

}  // namespace

void manufacture_sequence(const ManufactureOptions& o,
                          const std::function<void(const ManufactureProgress&)>& progress) {
  check_options(o);
  RunFolder folder(o.out_dir, {"--out", "manifest.yaml", "sequence", o.overwrite});
  Provenance provenance = start_provenance("manufacture", o.command_line);
  const fs::path& dir = folder.path();

  // ---- the object, the solver, the camera ----
  const PlacedObject object = place_object(o);
  sim::physics::VoxelizeOptions vo;
  vo.h_m = o.voxel_mm / 1000.0;
  vo.margin_cells = 3;
  vo.floor_at_mesh_bottom = true;
  const Grid3<float> fraction0 = sim::physics::voxelize_fraction(object.mesh, vo);
  sim::physics::EnthalpySolver solver(fraction0, o.physics);
  const render::Pinhole camera = overhead_camera(o, object.extent);

  create_output_directories(dir / "frames", "--out");
  create_output_directories(dir / "truth" / "masks", "--out");
  if (o.mesh_every > 0) create_output_directories(dir / "truth" / "meshes", "--out");
  sim::save_mesh(object.mesh, dir / "truth" / "initial_mesh.ply");

  // ---- the photos: melt to each photo's time, photograph, check the default segmentation ----
  const verify::SegmentationSettings defaults;
  Photographer photographer(camera, fraction0, o);
  std::ostringstream mass_csv;
  std::vector<std::string> images;
  mass_csv << "time_s,mass_g\n";
  json frames = json::array();
  const double mass0_g = solver.ice_mass_kg() * 1000.0;
  for (int k = 0; k < o.photos; ++k) {
    const double t = k * o.interval_s;
    if (t > solver.time_s()) solver.advance(t - solver.time_s());
    render::IcePhotoOptions po = o.photo;
    po.seed = o.seed * 1000003u + static_cast<std::uint64_t>(k);
    po.ground_seed = o.seed;
    const Photo photo = photographer.take(solver.ice_fraction(), po, o.width, o.height);
    const std::string name = fmt::format("frame_{:04d}.jpg", k + 1);
    render::write_jpeg(dir / "frames" / name, photo.image, o.jpeg_quality);
    verify::write_image(dir / "truth" / "masks" / fmt::format("frame_{:04d}.png", k + 1), photo.truth);
    // How well the verification loop's default segmentation recovers the true outline (of
    // the JPEG as written, so compression is included).
    const cv::Mat decoded = verify::read_image(dir / "frames" / name);
    const verify::Segmentation seg = verify::segment_image(decoded, defaults);
    const double true_area = cv::countNonZero(photo.truth);
    const double p = true_area > 0 || seg.area_px > 0 ? verify::compare_masks(photo.truth, seg.mask).P : 0.0;
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
    if (o.mesh_every > 0 && k % o.mesh_every == 0 && !photo.surface.F.empty())
      sim::save_mesh(photo.surface, dir / "truth" / "meshes" / fmt::format("frame_{:04d}.ply", k + 1));
    if (progress) progress({k + 1, o.photos, t, mass_g});
  }

  // ---- the truth, then the manifest ----
  write_text_atomically(dir / "mass.csv", mass_csv.str());
  json truth = truth_json(o, object, fraction0, mass0_g, solver, camera);
  truth["frames"] = frames;
  SequenceManifest manifest;
  manifest.comment = "Made by meltlab manufacture (physically based reference melt). Truth: truth/truth.json";
  manifest.object = fs::path(o.mesh).stem().string();
  manifest.interval_s = o.interval_s;
  manifest.camera = camera;
  manifest.mass_series = "mass.csv";
  manifest.images = images;
  finish_generated_sequence(folder, std::move(truth), provenance, manifest);
}

}  // namespace meltlab::experiments
