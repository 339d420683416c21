// OpenVDB at meltlab's edge (see vdb/openvdb.h). Compiling this file takes a while: OpenVDB is
// kept here and nowhere else.

#include <meltlab/render/vdb/openvdb.h>

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/RayIntersector.h>
#include <openvdb/tools/RayTracer.h>

#include <mutex>

namespace meltlab::render {

namespace fs = std::filesystem;

namespace {

void initialise() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::FloatGrid::Ptr to_grid(const Volume& v) {
  initialise();
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  auto acc = grid->getAccessor();
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) {
        const float x = v.value(i, j, k);
        if (x != 0.0f) acc.setValue(openvdb::Coord(i, j, k), x);
      }
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  m.preScale(openvdb::Vec3d(v.spacing().x(), v.spacing().y(), v.spacing().z()));
  m.postTranslate(openvdb::Vec3d(v.origin().x(), v.origin().y(), v.origin().z()));
  grid->setTransform(openvdb::math::Transform::createLinearTransform(m));
  grid->insertMeta("meltlab_placement",
                   openvdb::StringMetadata(v.placement() == SamplePlacement::kNodes ? "nodes" : "cell_centred"));
  grid->insertMeta("meltlab_dims", openvdb::Vec3IMetadata(openvdb::Vec3i(v.nx(), v.ny(), v.nz())));
  return grid;
}

/// meltlab's camera as OpenVDB's: the same ray for every pixel (OpenVDB's offset 0.5 is meltlab's
/// pixel centre at the integer).
class MeltlabCamera : public openvdb::tools::BaseCamera {
 public:
  MeltlabCamera(openvdb::tools::Film& film, const Camera& camera)
      : BaseCamera(film, openvdb::Vec3R(0), openvdb::Vec3R(0), 1.0, 1e-3, 1e30), gen_(camera) {}
  openvdb::math::Ray<double> getRay(size_t i, size_t j, double io, double jo) const override {
    const CameraRay r = gen_.generate_ray(double(i) + io - 0.5, double(j) + jo - 0.5);
    return openvdb::math::Ray<double>(openvdb::Vec3R(r.origin.x(), r.origin.y(), r.origin.z()),
                                      openvdb::Vec3R(r.direction.x(), r.direction.y(), r.direction.z()), 1e-9,
                                      std::numeric_limits<double>::max());
  }

 private:
  RayGenerator gen_;
};

}  // namespace

void write_vdb(const fs::path& file, const Volume& v) {
  const auto grid = to_grid(v);
  write_atomically(file, [&](const fs::path& tmp) {
    try {
      openvdb::io::File f(tmp.string());
      f.write({grid});
      f.close();
    } catch (const openvdb::Exception& e) {
      throw InputError(fmt::format("{}: cannot write: {}", file.string(), e.what()));
    }
  });
}

Volume read_vdb(const fs::path& file, const std::string& name) {
  initialise();
  check_input_file(file, "OpenVDB");
  openvdb::GridBase::Ptr base;
  try {
    openvdb::io::File f(file.string());
    f.open(false);  // no delayed loading: the file may change under us otherwise
    if (!name.empty()) {
      if (!f.hasGrid(name)) throw InputError(fmt::format("{}: no grid named '{}'", file.string(), name));
      base = f.readGrid(name);
    } else if (f.hasGrid("density")) {
      base = f.readGrid("density");
    } else {
      const auto grids = f.getGrids();
      for (const auto& g : *grids)
        if (g && g->isType<openvdb::FloatGrid>()) {
          if (base) throw InputError(fmt::format("{}: several float grids; name the one to read", file.string()));
          base = g;
        }
    }
    f.close();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: not a readable OpenVDB file: {}", file.string(), e.what()));
  }
  if (!base) throw InputError(fmt::format("{}: no float grid", file.string()));
  const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
  if (!grid) throw InputError(fmt::format("{}: grid '{}' is not a float grid", file.string(), base->getName()));
  const auto& map = *grid->transform().baseMap();
  if (!map.isLinear()) throw InputError(fmt::format("{}: the grid's transform is not linear", file.string()));
  const openvdb::Mat4d m = map.getAffineMap()->getMat4();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c && m(r, c) != 0.0)
        throw InputError(
            fmt::format("{}: the grid is rotated or sheared (only axis-aligned grids are read)", file.string()));
  openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
  if (box.empty()) throw InputError(fmt::format("{}: the grid has no active voxels", file.string()));
  const auto dim = box.dim();
  const std::int64_t count = checked_mul(checked_mul(dim.x(), dim.y()), dim.z());
  check_count(file.string(), "volume samples", count, input_limits().volume_samples, "volume_samples");
  Volume v = Volume::allocate(dim.x(), dim.y(), dim.z(), SampleType::kFloat32, file.string());
  v.set_value_scale(1.0);
  // LayoutXYZ is x fastest (offset i + j·nx + k·nx·ny): meltlab's order.
  openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, static_cast<float*>(v.mutable_data()));
  openvdb::tools::copyToDense(*grid, dense);
  const auto* values = static_cast<const float*>(v.data());
  for (std::int64_t i = 0; i < count; ++i)
    if (!std::isfinite(values[i]))
      throw InputError(fmt::format("{}: the grid holds a value that is not finite", file.string()));
  const openvdb::Vec3d lo = grid->indexToWorld(box.min());
  const openvdb::Vec3d vs = grid->voxelSize();
  v.set_origin(Eigen::Vector3d(lo.x(), lo.y(), lo.z()));
  v.set_spacing(Eigen::Vector3d(vs.x(), vs.y(), vs.z()));
  const auto placement = grid->getMetadata<openvdb::StringMetadata>("meltlab_placement");
  v.set_placement(placement && placement->value() == "nodes" ? SamplePlacement::kNodes : SamplePlacement::kCellCentred);
  return v;
}

// ---- the peer renderer -------------------------------------------------------------------------

struct OpenVdbPeer::Impl {
  openvdb::FloatGrid::Ptr grid;
};

OpenVdbPeer::OpenVdbPeer(const Volume& volume) : impl_(std::make_unique<Impl>()) { impl_->grid = to_grid(volume); }

OpenVdbPeer::OpenVdbPeer(const Volume& v, const std::function<float(float)>& density)
    : impl_(std::make_unique<Impl>()) {
  initialise();
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  // Slabs of x, z fastest (OpenVDB's LayoutZYX); the density of each stored value once (8-bit volumes).
  std::vector<float> lut;
  if (v.type() == SampleType::kUint8) {
    lut.resize(256);
    for (int i = 0; i < 256; ++i) lut[std::size_t(i)] = density(float(i) * float(v.value_scale()));
  }
  constexpr int kSlab = 16;
  std::vector<float> slab(std::size_t(kSlab) * std::size_t(v.ny()) * std::size_t(v.nz()));
  for (int x0 = 0; x0 < v.nx(); x0 += kSlab) {
    const int x1 = std::min(v.nx(), x0 + kSlab);
    const openvdb::CoordBBox box(openvdb::Coord(x0, 0, 0), openvdb::Coord(x1 - 1, v.ny() - 1, v.nz() - 1));
    visit_samples(v, [&](const auto& s) {
      for (int x = x0; x < x1; ++x)
        for (int y = 0; y < v.ny(); ++y)
          for (int z = 0; z < v.nz(); ++z) {
            const auto stored = s.data[x * s.sx + y * s.sy + z * s.sz];
            slab[(std::size_t(x - x0) * std::size_t(v.ny()) + std::size_t(y)) * std::size_t(v.nz()) + std::size_t(z)] =
                lut.empty() ? density(float(stored) * s.scale) : lut[std::size_t(stored)];
          }
      return 0;
    });
    openvdb::tools::Dense<float, openvdb::tools::LayoutZYX> dense(box, slab.data());
    openvdb::tools::copyFromDense(dense, *grid, 0.0f);
  }
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  m.preScale(openvdb::Vec3d(v.spacing().x(), v.spacing().y(), v.spacing().z()));
  m.postTranslate(openvdb::Vec3d(v.origin().x(), v.origin().y(), v.origin().z()));
  grid->setTransform(openvdb::math::Transform::createLinearTransform(m));
  grid->pruneGrid();
  impl_->grid = grid;
}
OpenVdbPeer::~OpenVdbPeer() = default;

std::int64_t OpenVdbPeer::active_voxels() const { return std::int64_t(impl_->grid->activeVoxelCount()); }
std::int64_t OpenVdbPeer::memory_bytes() const { return std::int64_t(impl_->grid->memUsage()); }

ImageF OpenVdbPeer::render(const Camera& camera, const OpenVdbRenderSettings& s, ImageF* alpha) const {
  const int W = camera_width(camera), H = camera_height(camera);
  openvdb::tools::Film film{std::size_t(W), std::size_t(H)};
  MeltlabCamera cam(film, camera);
  openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid> intersector(*impl_->grid);
  openvdb::tools::VolumeRender<openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid>> renderer(intersector, cam);
  const Eigen::Vector3d l = s.to_light.normalized();
  renderer.setLightDir(l.x(), l.y(), l.z());
  renderer.setLightColor(s.light_colour.x(), s.light_colour.y(), s.light_colour.z());
  renderer.setPrimaryStep(s.primary_step_voxels);
  renderer.setShadowStep(s.shadow_step_voxels);
  const double scatter = s.extinction_per_voxel * s.albedo, absorb = s.extinction_per_voxel - scatter;
  renderer.setScattering(scatter, scatter, scatter);
  renderer.setAbsorption(absorb, absorb, absorb);
  renderer.setLightGain(0.0);
  renderer.setCutOff(s.cutoff);
  renderer.render(s.threaded);
  ImageF out(W, H, 3);
  if (alpha) *alpha = ImageF(W, H, 1);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const auto& p = film.pixel(std::size_t(x), std::size_t(y));
      out.at(x, y, 0) = p.r;
      out.at(x, y, 1) = p.g;
      out.at(x, y, 2) = p.b;
      if (alpha) alpha->at(x, y) = p.a;
    }
  return out;
}

}  // namespace meltlab::render
