// The renderer's texture lookups, bilinear or MIP-mapped (texture/lookup.h).

#include <meltlab/render/texture/lookup.h>
#include <meltlab/render/texture/filtered.h>
#include <meltlab/core/image.h>

#include <utility>

namespace meltlab::render {

namespace {

class BilinearImage final : public ImageTexture {
 public:
  explicit BilinearImage(RgbImage image) : image_(std::move(image)) {}
  Rgb lookup(const Eigen::Vector2d& st, const Differential2* /*footprint*/) const override {
    return sample_bilinear_rgb(image_, st.x() * image_.width() - 0.5, st.y() * image_.height() - 0.5,
                               ImageWrap::kRepeat, ImageWrap::kRepeat);
  }

 private:
  RgbImage image_;
};

class BilinearEnvironment final : public EnvironmentTexture {
 public:
  explicit BilinearEnvironment(RgbImage latlong) : latlong_(std::move(latlong)) {}
  Rgb lookup(const Eigen::Vector3d& dir, const Differential* /*footprint*/) const override {
    return sample_latlong(latlong_, dir);
  }

 private:
  RgbImage latlong_;
};

class MipmapImage final : public ImageTexture {
 public:
  MipmapImage(std::shared_ptr<const FilteredTextures> filtered, int id) : filtered_(std::move(filtered)), id_(id) {}
  Rgb lookup(const Eigen::Vector2d& st, const Differential2* footprint) const override {
    const Differential2 d = footprint ? *footprint : Differential2{};
    return filtered_->texture(id_, st.x(), st.y(), d.dx, d.dy);
  }

 private:
  std::shared_ptr<const FilteredTextures> filtered_;
  int id_;
};

class MipmapEnvironment final : public EnvironmentTexture {
 public:
  MipmapEnvironment(std::shared_ptr<const FilteredTextures> filtered, int id)
      : filtered_(std::move(filtered)), id_(id) {}
  Rgb lookup(const Eigen::Vector3d& dir, const Differential* footprint) const override {
    const Differential d = footprint ? *footprint : Differential{};
    return filtered_->environment(id_, dir, d.dx, d.dy);
  }

 private:
  std::shared_ptr<const FilteredTextures> filtered_;
  int id_;
};

}  // namespace

TextureFactory::TextureFactory(TextureFilter filter) : filter_(filter) {
  if (filter_ == TextureFilter::kMipmap) filtered_ = std::make_shared<FilteredTextures>();
}
TextureFactory::~TextureFactory() = default;

std::unique_ptr<const ImageTexture> TextureFactory::image(RgbImage image, const std::string& name) {
  if (!filtered_) return std::make_unique<BilinearImage>(std::move(image));
  return std::make_unique<MipmapImage>(filtered_, filtered_->add(image, FilteredTextures::Kind::kTexture, name));
}

std::unique_ptr<const EnvironmentTexture> TextureFactory::environment(RgbImage latlong, const std::string& name) {
  if (!filtered_) return std::make_unique<BilinearEnvironment>(std::move(latlong));
  return std::make_unique<MipmapEnvironment>(
      filtered_, filtered_->add(latlong, FilteredTextures::Kind::kLatLongEnvironment, name));
}

int dominant_axis(const Eigen::Vector3d& ng) {
  const Eigen::Vector3d a = ng.cwiseAbs();
  return a.x() > a.y() ? (a.x() > a.z() ? 0 : 2) : (a.y() > a.z() ? 1 : 2);
}

Rgb lookup_projected(const ImageTexture& texture, const Eigen::Vector3d& x, int axis, double tile,
                     const Differential* dx) {
  auto uv = [&](const Eigen::Vector3d& q) {
    return Eigen::Vector2d((axis == 0 ? q.y() : q.x()) / tile, (axis == 2 ? q.y() : q.z()) / tile);
  };
  if (!dx) return texture.lookup(uv(x), nullptr);
  const Differential2 d{uv(dx->dx), uv(dx->dy)};
  return texture.lookup(uv(x), &d);
}

}  // namespace meltlab::render
