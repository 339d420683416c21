// Seed 003's gradient volume (see slicing/gradient_volume.h).

#include <meltlab/render/slicing/gradient_volume.h>

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>
#include <meltlab/core/time.h>
#include <meltlab/render/volume/generate.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>

namespace meltlab::render {

namespace {

struct Offset {
  int x, y, z;
  float wx, wy, wz;  // o / |o|
};

std::vector<Offset> offsets(int r, GradientNeighbourhood nb) {
  std::vector<Offset> out;
  for (int z = -r; z <= r; ++z)
    for (int y = -r; y <= r; ++y)
      for (int x = -r; x <= r; ++x) {
        if (!x && !y && !z) continue;
        const double len = std::sqrt(double(x * x + y * y + z * z));
        if (nb == GradientNeighbourhood::kBall && len > r) continue;
        out.push_back({x, y, z, float(x / len), float(y / len), float(z / len)});
      }
  return out;
}

void check_options(const GradientOptions& o) {
  if (o.radius < 1 || o.radius > 4)
    throw InputError(fmt::format("slicing: the gradient radius must be in [1, 4] (got {})", o.radius));
  if (o.bits != 4 && o.bits != 8)
    throw InputError(fmt::format("slicing: the gradient encoding has 8 or 4 bits (got {})", o.bits));
}

constexpr char kMagic[8] = {'M', 'L', 'G', 'R', 'A', 'D', '0', '1'};

}  // namespace

double gradient_normaliser(int radius, GradientNeighbourhood nb) {
  double k = 0;
  for (const Offset& o : offsets(radius, nb))
    k += double(o.x) * o.x / std::sqrt(double(o.x * o.x + o.y * o.y + o.z * o.z));
  return k;
}

std::vector<Eigen::Vector3f> estimate_gradients(const Volume& volume, int radius, GradientNeighbourhood nb) {
  const Volume f = volume.type() == SampleType::kFloat32 && volume.x_fastest_packed() ? volume : volume.to_float32();
  const auto s = f.samples<float>();
  const int nx = s.nx, ny = s.ny, nz = s.nz;
  const auto offs = offsets(radius, nb);
  std::vector<Eigen::Vector3f> g(std::size_t(f.sample_count()));
  tbb::parallel_for(0, nz, [&](int k) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const float c = s.at(i, j, k);
        float gx = 0, gy = 0, gz = 0;
        const bool inner =
            i >= radius && j >= radius && k >= radius && i + radius < nx && j + radius < ny && k + radius < nz;
        for (const Offset& o : offs) {
          const float d = inner ? s.at(i + o.x, j + o.y, k + o.z) - c
                                : s.at(std::clamp(i + o.x, 0, nx - 1), std::clamp(j + o.y, 0, ny - 1),
                                       std::clamp(k + o.z, 0, nz - 1)) -
                                      c;
          gx += o.wx * d;
          gy += o.wy * d;
          gz += o.wz * d;
        }
        g[std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * std::size_t(k))] =
            Eigen::Vector3f(gx, gy, gz);
      }
  });
  return g;
}

VolumeSamples<std::uint8_t> GradientVolume::channel(int c) const {
  VolumeSamples<std::uint8_t> s;
  s.data = encoded.data() + c;
  s.nx = dims[0], s.ny = dims[1], s.nz = dims[2];
  s.sx = 3, s.sy = 3 * std::int64_t(dims[0]), s.sz = 3 * std::int64_t(dims[0]) * dims[1];
  s.scale = 1.0f / float(levels());
  return s;
}

Eigen::Vector3d GradientVolume::decoded(int i, int j, int k) const {
  const std::size_t o = 3 * (std::size_t(i) + std::size_t(dims[0]) * (std::size_t(j) + std::size_t(dims[1]) * k));
  const double L = levels();
  return Eigen::Vector3d(2 * encoded[o] / L - 1, 2 * encoded[o + 1] / L - 1, 2 * encoded[o + 2] / L - 1);
}

GradientVolume encode_gradients(const std::vector<Eigen::Vector3f>& g, const std::array<int, 3>& dims,
                                const GradientOptions& options) {
  check_options(options);
  GradientVolume out;
  out.dims = dims;
  out.options = options;
  double m = 0;
  for (const auto& v : g) m = std::max(m, double(v.norm()));
  out.max_magnitude = m;
  out.encoded.resize(3 * g.size());
  const double L = out.levels();
  const double inv = m > 0 ? 1.0 / m : 0.0;
  tbb::parallel_for(std::size_t(0), g.size(), [&](std::size_t i) {
    for (int c = 0; c < 3; ++c) {
      const double e = 0.5 + 0.5 * double(g[i][c]) * inv;
      out.encoded[3 * i + std::size_t(c)] = std::uint8_t(std::lround(std::clamp(e, 0.0, 1.0) * L));
    }
  });
  return out;
}

GradientVolume build_gradient_volume(const Volume& volume, const GradientOptions& options) {
  check_options(options);
  const auto t0 = std::chrono::steady_clock::now();
  GradientVolume out =
      encode_gradients(estimate_gradients(volume, options.radius, options.neighbourhood), volume.dims(), options);
  out.build_ms = ms_since(t0);
  return out;
}

std::string gradient_cache_name(const Volume& volume, const GradientOptions& o) {
  ContentHash h;
  h.add_field("meltlab slicing gradients v1");
  h.add_field(volume_content_hash(volume));
  h.add_field(fmt::format("{:.17g}", volume.value_scale()));
  h.add_field(fmt::format("r{} {} bits{}", o.radius, o.neighbourhood == GradientNeighbourhood::kBall ? "ball" : "cube",
                          o.bits));
  return h.hex() + ".grad";
}

GradientVolume cached_gradient_volume(const Volume& volume, const GradientOptions& options,
                                      const std::filesystem::path& cache_dir) {
  check_options(options);
  if (cache_dir.empty()) return build_gradient_volume(volume, options);
  const auto t0 = std::chrono::steady_clock::now();
  const std::filesystem::path file = cache_dir / gradient_cache_name(volume, options);
  const std::size_t n = 3 * std::size_t(volume.sample_count());
  // File: magic (8 bytes), nx ny nz bits (4 x int32), max |g| (double), 3 n bytes.
  const std::size_t header = 8 + 16 + 8;
  std::error_code ec;
  if (std::filesystem::is_regular_file(file, ec) && std::filesystem::file_size(file, ec) == header + n) {
    std::ifstream in(file, std::ios::binary);
    char magic[8];
    std::int32_t d[4];
    double m = 0;
    in.read(magic, 8);
    in.read(reinterpret_cast<char*>(d), sizeof d);
    in.read(reinterpret_cast<char*>(&m), sizeof m);
    if (in && std::memcmp(magic, kMagic, 8) == 0 && d[0] == volume.nx() && d[1] == volume.ny() && d[2] == volume.nz() &&
        d[3] == options.bits && std::isfinite(m) && m >= 0) {
      GradientVolume g;
      g.dims = volume.dims();
      g.options = options;
      g.max_magnitude = m;
      g.encoded.resize(n);
      in.read(reinterpret_cast<char*>(g.encoded.data()), std::streamsize(n));
      const int top = g.levels();
      if (in && std::all_of(g.encoded.begin(), g.encoded.end(), [top](std::uint8_t v) { return v <= top; })) {
        g.from_cache = true;
        g.build_ms = ms_since(t0);
        return g;
      }
    }
    spdlog::warn("slicing: the gradient cache file {} is malformed; recomputing it", file.string());
  }
  GradientVolume g = build_gradient_volume(volume, options);
  std::filesystem::create_directories(cache_dir, ec);
  if (ec)
    throw InputError(fmt::format("{}: cannot create the gradient cache folder: {}", cache_dir.string(), ec.message()));
  write_atomically(file, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    const std::int32_t d[4] = {volume.nx(), volume.ny(), volume.nz(), options.bits};
    out.write(kMagic, 8);
    out.write(reinterpret_cast<const char*>(d), sizeof d);
    out.write(reinterpret_cast<const char*>(&g.max_magnitude), sizeof g.max_magnitude);
    out.write(reinterpret_cast<const char*>(g.encoded.data()), std::streamsize(n));
    if (!out) throw InputError(fmt::format("{}: cannot write the gradient cache file", file.string()));
  });
  g.build_ms = ms_since(t0);
  return g;
}

}  // namespace meltlab::render
