// The liquid mask (liquid_mask.h): spreading filter (Eq. 7.12/7.13) and deposit pass (§7.3.2).

#include <meltlab/core/error.h>
#include <meltlab/sim/liquid_mask.h>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace meltlab::sim {

void LiquidMaskParams::validate() const {
  auto bad = [](const char* what, const std::string& why) {
    throw InputError(fmt::format("liquid mask: '{}' {}", what, why));
  };
  if (width < 5 || width > 16384) bad("width", fmt::format("must be in [5, 16384] (got {})", width));
  if (height < 5 || height > 16384) bad("height", fmt::format("must be in [5, 16384] (got {})", height));
  if (!(texel_size > 0.0) || !std::isfinite(texel_size)) bad("texel_size", "must be a finite number > 0");
  if (!origin.allFinite()) bad("origin", "must be finite");
  if (!(far_fraction > 0.0 && far_fraction <= 1.0))
    bad("far_fraction", fmt::format("must be in (0, 1] (got {})", far_fraction));
  if (!(deposit_value > 0.0f) || !std::isfinite(deposit_value)) bad("deposit_value", "must be a finite number > 0");
  if (!(threshold > 0.0f) || !std::isfinite(threshold)) bad("threshold", "must be a finite number > 0");
}

LiquidMaskParams LiquidMaskParams::around(const IndexedMesh& mesh, int resolution, double extent_factor) {
  LiquidMaskParams p;
  p.width = p.height = resolution;
  Eigen::Vector2d lo(std::numeric_limits<double>::max(), std::numeric_limits<double>::max());
  Eigen::Vector2d hi = -lo;
  for (const auto& v : mesh.V) {
    lo = lo.cwiseMin(v.head<2>());
    hi = hi.cwiseMax(v.head<2>());
  }
  if (mesh.V.empty()) lo = hi = Eigen::Vector2d::Zero();
  const double side = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1e-12}) * extent_factor;
  p.texel_size = side / resolution;
  p.origin = 0.5 * (lo + hi) - Eigen::Vector2d(0.5 * side, 0.5 * side);
  return p;
}

// ---- spreading ----------------------------------------------------------------------

namespace {
constexpr std::array<int, 4> kTaps{-2, -1, 1, 2};  // the non-zero columns/rows of Eq. 7.12

// Horizontal half of the separable filter for rows [r0, r1): tmp(i, j) = Σ_di m(i+di, j).
void spread_rows(const float* in, float* tmp, int w, int r0, int r1) {
  for (int j = r0; j < r1; ++j) {
    const float* row = in + static_cast<std::size_t>(j) * w;
    float* t = tmp + static_cast<std::size_t>(j) * w;
    for (int i = 0; i < w; ++i) {
      float s = 0.0f;
      for (int d : kTaps) {
        const int k = i + d;
        if (k >= 0 && k < w) s += row[k];
      }
      t[i] = s;
    }
  }
}
// Vertical half: out(i, j) = Σ_dj tmp(i, j+dj) / 16.
void spread_cols(const float* tmp, float* out, int w, int h, int r0, int r1) {
  for (int j = r0; j < r1; ++j) {
    float* o = out + static_cast<std::size_t>(j) * w;
    for (int i = 0; i < w; ++i) o[i] = 0.0f;
    for (int d : kTaps) {
      const int k = j + d;
      if (k < 0 || k >= h) continue;
      const float* t = tmp + static_cast<std::size_t>(k) * w;
      for (int i = 0; i < w; ++i) o[i] += t[i];
    }
    for (int i = 0; i < w; ++i) o[i] *= 1.0f / 16.0f;
  }
}
}  // namespace

void spread_mask(const std::vector<float>& in, std::vector<float>& out, int width, int height, bool parallel) {
  const std::size_t n = static_cast<std::size_t>(width) * height;
  if (in.size() != n) throw InvariantError("spread_mask: grid size does not match width x height");
  std::vector<float> tmp(n);
  out.assign(n, 0.0f);
  if (parallel) {
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 16), [&](const tbb::blocked_range<int>& r) {
      spread_rows(in.data(), tmp.data(), width, r.begin(), r.end());
    });
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 16), [&](const tbb::blocked_range<int>& r) {
      spread_cols(tmp.data(), out.data(), width, height, r.begin(), r.end());
    });
  } else {
    spread_rows(in.data(), tmp.data(), width, 0, height);
    spread_cols(tmp.data(), out.data(), width, height, 0, height);
  }
}

void spread_mask_bilinear4(const std::vector<float>& in, std::vector<float>& out, int width, int height) {
  const std::size_t n = static_cast<std::size_t>(width) * height;
  if (in.size() != n) throw InvariantError("spread_mask_bilinear4: grid size does not match width x height");
  out.assign(n, 0.0f);
  auto texel = [&](int i, int j) -> float {
    return (i < 0 || j < 0 || i >= width || j >= height) ? 0.0f : in[static_cast<std::size_t>(j) * width + i];
  };
  // Bilinear filtering with texel centres at integer coordinates and a zero border.
  auto bilinear = [&](double x, double y) -> float {
    const double x0 = std::floor(x), y0 = std::floor(y);
    const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
    const int i = static_cast<int>(x0), j = static_cast<int>(y0);
    const float top = texel(i, j) * (1.0f - fx) + texel(i + 1, j) * fx;
    const float bottom = texel(i, j + 1) * (1.0f - fx) + texel(i + 1, j + 1) * fx;
    return top * (1.0f - fy) + bottom * fy;
  };
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const float s = bilinear(i - 1.5, j - 1.5) + bilinear(i - 1.5, j + 1.5) + bilinear(i + 1.5, j - 1.5) +
                      bilinear(i + 1.5, j + 1.5);
      out[static_cast<std::size_t>(j) * width + i] = s * 0.25f;
    }
}

// ---- deposit ------------------------------------------------------------------------

template <class Real>
double deposit_slab_top(const TriMesh<Real>& mesh, double far_fraction) {
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  bool any = false;
  for (std::size_t t = 0; t < mesh.triangle_slots(); ++t) {
    if (!mesh.triangle_alive[t]) continue;
    any = true;
    for (Index v : mesh.triangle[t]) {
      const double z = static_cast<double>(mesh.position[static_cast<std::size_t>(v)].z());
      zmin = std::min(zmin, z);
      zmax = std::max(zmax, z);
    }
  }
  if (!any) return std::numeric_limits<double>::quiet_NaN();
  return zmin + far_fraction * (zmax - zmin);
}

namespace {
// Fills the texels whose centres lie inside the (either-orientation) triangle a, b, c given in
// texel coordinates, in which the centre of texel (i, j) is the point (i, j).
void fill_triangle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, int w, int h,
                   std::vector<std::uint8_t>& fp) {
  const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  if (area == 0.0) return;
  const double sgn = area > 0 ? 1.0 : -1.0;
  // Clamp in double before converting, so a triangle far off the grid cannot overflow int.
  auto lo = [](double x, int n) { return static_cast<int>(std::ceil(std::clamp(x, -1.0, static_cast<double>(n)))); };
  auto hi = [](double x, int n) { return static_cast<int>(std::floor(std::clamp(x, -1.0, static_cast<double>(n)))); };
  const int i0 = std::max(0, lo(std::min({a.x(), b.x(), c.x()}), w));
  const int i1 = std::min(w - 1, hi(std::max({a.x(), b.x(), c.x()}), w));
  const int j0 = std::max(0, lo(std::min({a.y(), b.y(), c.y()}), h));
  const int j1 = std::min(h - 1, hi(std::max({a.y(), b.y(), c.y()}), h));
  auto edge = [sgn](const Eigen::Vector2d& p, const Eigen::Vector2d& q, double x, double y) {
    return sgn * ((q.x() - p.x()) * (y - p.y()) - (q.y() - p.y()) * (x - p.x()));
  };
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double x = i, y = j;
      if (edge(a, b, x, y) >= 0 && edge(b, c, x, y) >= 0 && edge(c, a, x, y) >= 0)
        fp[static_cast<std::size_t>(j) * w + i] = 1;
    }
}
}  // namespace

template <class Real>
std::vector<std::uint8_t> footprint_below(const TriMesh<Real>& mesh, const LiquidMaskParams& params,
                                          double slab_top_z) {
  const int w = params.width, h = params.height;
  std::vector<std::uint8_t> fp(static_cast<std::size_t>(w) * h, 0);
  if (!std::isfinite(slab_top_z)) return fp;
  // World (x, y) -> texel coordinates with texel centres at integers.
  auto to_texel = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d((p.x() - params.origin.x()) / params.texel_size - 0.5,
                           (p.y() - params.origin.y()) / params.texel_size - 0.5);
  };
  std::array<Eigen::Vector3d, 3> tri;
  std::array<Eigen::Vector3d, 4> poly;
  for (std::size_t t = 0; t < mesh.triangle_slots(); ++t) {
    if (!mesh.triangle_alive[t]) continue;
    int below = 0;
    for (int k = 0; k < 3; ++k) {
      tri[static_cast<std::size_t>(k)] =
          mesh.position[static_cast<std::size_t>(mesh.triangle[t][static_cast<std::size_t>(k)])]
              .template cast<double>();
      below += tri[static_cast<std::size_t>(k)].z() <= slab_top_z;
    }
    if (below == 0) continue;
    // Clip to z <= slab_top_z (Sutherland–Hodgman against one plane: at most 4 vertices).
    int n = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = tri[k];
      const Eigen::Vector3d& q = tri[(k + 1) % 3];
      const bool pin = p.z() <= slab_top_z, qin = q.z() <= slab_top_z;
      if (pin) poly[static_cast<std::size_t>(n++)] = p;
      if (pin != qin) {
        const double s = (slab_top_z - p.z()) / (q.z() - p.z());
        poly[static_cast<std::size_t>(n++)] = p + s * (q - p);
      }
    }
    const Eigen::Vector2d a = to_texel(poly[0]);
    for (int k = 1; k + 1 < n; ++k)
      fill_triangle(a, to_texel(poly[static_cast<std::size_t>(k)]), to_texel(poly[static_cast<std::size_t>(k + 1)]), w,
                    h, fp);
  }
  return fp;
}

template std::vector<std::uint8_t> footprint_below(const TriMesh<double>&, const LiquidMaskParams&, double);
template std::vector<std::uint8_t> footprint_below(const TriMesh<float>&, const LiquidMaskParams&, double);
template double deposit_slab_top(const TriMesh<double>&, double);
template double deposit_slab_top(const TriMesh<float>&, double);

// ---- the mask -----------------------------------------------------------------------

LiquidMask::LiquidMask(LiquidMaskParams params) : params_(std::move(params)) {
  params_.validate();
  values_.assign(static_cast<std::size_t>(params_.width) * params_.height, 0.0f);
}

void LiquidMask::set_threshold_texture(std::vector<float> tp) {
  if (!tp.empty() && tp.size() != values_.size())
    throw InputError(
        fmt::format("liquid mask: threshold texture has {} texels, the mask {}", tp.size(), values_.size()));
  for (float v : tp)
    if (!(v > 0.0f) || !std::isfinite(v))
      throw InputError("liquid mask: threshold texture values must be finite and > 0");
  tp_ = std::move(tp);
}

void LiquidMask::spread(bool parallel) {
  spread_mask(values_, scratch_, params_.width, params_.height, parallel);
  values_.swap(scratch_);
}

namespace {
template <class Real>
std::int64_t deposit_impl(const TriMesh<Real>& mesh, const LiquidMaskParams& p, std::vector<float>& values) {
  const double top = deposit_slab_top(mesh, p.far_fraction);
  if (!std::isfinite(top)) return 0;
  const auto fp = footprint_below(mesh, p, top);
  std::int64_t n = 0;
  for (std::size_t k = 0; k < fp.size(); ++k) {
    if (!fp[k]) continue;
    ++n;
    values[k] = p.blend == DepositBlend::kOverwrite ? p.deposit_value : values[k] + p.deposit_value;
  }
  return n;
}
}  // namespace

std::int64_t LiquidMask::deposit(const TriMesh<double>& mesh) {
  return last_footprint_ = deposit_impl(mesh, params_, values_);
}
std::int64_t LiquidMask::deposit(const TriMesh<float>& mesh) {
  return last_footprint_ = deposit_impl(mesh, params_, values_);
}

void LiquidMask::step(const TriMesh<double>& mesh, bool parallel) {
  spread(parallel);
  deposit(mesh);
  ++cycles_;
}
void LiquidMask::step(const TriMesh<float>& mesh, bool parallel) {
  spread(parallel);
  deposit(mesh);
  ++cycles_;
}

std::int64_t LiquidMask::wet_count() const {
  std::int64_t n = 0;
  for (int j = 0; j < params_.height; ++j)
    for (int i = 0; i < params_.width; ++i) n += wet(i, j);
  return n;
}

double LiquidMask::total() const {
  double s = 0.0;
  for (float v : values_) s += static_cast<double>(v);
  return s;
}

float LiquidMask::max_value() const {
  return values_.empty() ? 0.0f : *std::max_element(values_.begin(), values_.end());
}

}  // namespace meltlab::sim
