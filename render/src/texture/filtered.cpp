// Filtered lookups through OpenImageIO's TextureSystem (texture/filtered.h).

#include <meltlab/render/texture/filtered.h>
#include <meltlab/core/error.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <vector>

namespace meltlab::render {

namespace {

// One TextureSystem for the process, never destroyed: OpenImageIO's per-thread tile caches
// outlive a TextureSystem torn down while pool threads still hold its tiles (creating and
// destroying one per renderer aborts in ImageCache::decr_tiles within a few frames).
// Each FilteredTextures owns its files and invalidates them when it goes.
OIIO::TextureSystem* texture_system() {
  static OIIO::TextureSystem* const ts = [] {
    OIIO::TextureSystem* t = OIIO::TextureSystem::create(/*shared=*/false);
    // make_texture writes the lat-long files without an up direction: ours is z.
    t->attribute("latlong_up", "z");
    return t;
  }();
  return ts;
}

}  // namespace

struct FilteredTextures::Impl {
  OIIO::TextureSystem* ts = texture_system();
  std::filesystem::path dir;  ///< the private directory of the texture files
  struct Entry {
    OIIO::TextureSystem::TextureHandle* handle = nullptr;
    Kind kind = Kind::kTexture;
  };
  std::vector<Entry> entries;
  std::vector<std::filesystem::path> files;

  Impl() {
    std::string pattern = (std::filesystem::temp_directory_path() / "meltlab-textures-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw InputError(fmt::format("{}: cannot make a texture directory", pattern));
    dir = pattern;
  }
  ~Impl() {
    for (const auto& f : files) ts->invalidate(OIIO::ustring(f.string()));
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }

  OIIO::TextureOpt options(Kind kind) const {
    OIIO::TextureOpt opt;
    opt.interpmode = OIIO::TextureOpt::InterpBilinear;  // the bilinear path's interpolation
    opt.mipmode = OIIO::TextureOpt::MipModeAniso;
    if (kind == Kind::kTexture) opt.swrap = opt.twrap = OIIO::TextureOpt::WrapPeriodic;
    return opt;
  }
};

FilteredTextures::FilteredTextures() : impl_(std::make_unique<Impl>()) {}
FilteredTextures::~FilteredTextures() = default;

int FilteredTextures::add(const RgbImage& image, Kind kind, const std::string& name) {
  if (image.width() <= 0 || image.height() <= 0 || image.channels() != 3)
    throw InputError(fmt::format("{}: the image holds no pixels", name));
  const std::filesystem::path file =
      impl_->dir /
      fmt::format("{}.tx",
                  impl_->entries.size());  // TIFF: OpenEXR would force its y-up, border-sampled lat-long convention
  OIIO::ImageSpec spec(image.width(), image.height(), 3, OIIO::TypeDesc::FLOAT);
  const OIIO::ImageBuf src(spec, const_cast<float*>(image.data()));  // wraps, read only
  OIIO::ImageSpec config;
  config.tile_width = config.tile_height = 64;
  config.set_format(OIIO::TypeDesc::FLOAT);
  config.attribute("maketx:filtername", "box");
  config.attribute("maketx:highlightcomp", 0);
  const auto mode = kind == Kind::kTexture ? OIIO::ImageBufAlgo::MakeTxTexture : OIIO::ImageBufAlgo::MakeTxEnvLatl;
  if (!OIIO::ImageBufAlgo::make_texture(mode, src, file.string(), config))
    throw InputError(fmt::format("{}: cannot make a MIP-mapped texture: {}", name, OIIO::geterror()));
  impl_->files.push_back(file);
  Impl::Entry e;
  e.kind = kind;
  e.handle = impl_->ts->get_texture_handle(OIIO::ustring(file.string()));
  if (!e.handle)
    throw InputError(fmt::format("{}: the texture system cannot open it: {}", name, impl_->ts->geterror()));
  impl_->entries.push_back(e);
  return static_cast<int>(impl_->entries.size()) - 1;
}

Eigen::Vector3d FilteredTextures::texture(int id, double s, double t, const Eigen::Vector2d& dst_dx,
                                          const Eigen::Vector2d& dst_dy) const {
  const Impl::Entry& e = impl_->entries.at(static_cast<std::size_t>(id));
  OIIO::TextureOpt opt = impl_->options(e.kind);
  float out[3] = {0, 0, 0};
  impl_->ts->texture(e.handle, impl_->ts->get_perthread_info(), opt, static_cast<float>(s), static_cast<float>(t),
                     static_cast<float>(dst_dx.x()), static_cast<float>(dst_dx.y()), static_cast<float>(dst_dy.x()),
                     static_cast<float>(dst_dy.y()), 3, out);
  return {out[0], out[1], out[2]};
}

Eigen::Vector3d FilteredTextures::environment(int id, const Eigen::Vector3d& dir, const Eigen::Vector3d& ddir_dx,
                                              const Eigen::Vector3d& ddir_dy) const {
  const Impl::Entry& e = impl_->entries.at(static_cast<std::size_t>(id));
  OIIO::TextureOpt opt = impl_->options(e.kind);
  auto v3 = [](const Eigen::Vector3d& v) {
    return OIIO::V3fParam(static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z()));
  };
  float out[3] = {0, 0, 0};
  impl_->ts->environment(e.handle, impl_->ts->get_perthread_info(), opt, v3(dir), v3(ddir_dx), v3(ddir_dy), 3, out);
  return {out[0], out[1], out[2]};
}

}  // namespace meltlab::render
