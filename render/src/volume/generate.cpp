// Perlin's improved noise, turbulence and the generated volumes (see volume/generate.h).

#include <meltlab/render/volume/generate.h>

#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string_view>
#include <vector>

namespace meltlab::render {

namespace {

// Ken Perlin's reference permutation (2002), doubled to 512 entries so that p[p[x] + y] needs no
// wrap-around.
constexpr std::array<std::uint8_t, 256> kPermutation = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103, 30,  69,  142,
    8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,  197, 62,  94,  252, 219, 203,
    117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174, 20,  125, 136, 171, 168, 68,  175, 74,  165,
    71,  134, 139, 48,  27,  166, 77,  146, 158, 231, 83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,
    55,  46,  245, 40,  244, 102, 143, 54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,
    18,  169, 200, 196, 135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250,
    124, 123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,  182, 189,
    28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,
    129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,
    242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,  51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,
    181, 199, 106, 157, 184, 84,  204, 176, 115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114,
    67,  29,  24,  72,  243, 141, 128, 195, 78,  66,  215, 61,  156, 180};

constexpr std::array<int, 512> doubled() {
  std::array<int, 512> p{};
  for (int i = 0; i < 512; ++i) p[std::size_t(i)] = kPermutation[std::size_t(i & 255)];
  return p;
}
constexpr std::array<int, 512> kP = doubled();

inline double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }
inline double lerp(double t, double a, double b) { return a + t * (b - a); }
/// The dot product of (x, y, z) with one of the 12 cube-edge gradients (16 with 4 repeated).
inline double grad(int hash, double x, double y, double z) {
  const int h = hash & 15;
  const double u = h < 8 ? x : y;
  const double v = h < 4 ? y : (h == 12 || h == 14 ? x : z);
  return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
}

/// The domain offset of octave k for a seed: three numbers in [0, 256) (the noise has period 256).
std::array<double, 3> octave_offset(std::uint64_t seed, int k) {
  if (seed == 0) return {0, 0, 0};
  std::array<double, 3> o{};
  std::uint64_t h = splitmix64(seed ^ (0x6f63746176650000ull + std::uint64_t(k)));
  for (auto& x : o) {
    h = splitmix64(h);
    x = 256.0 * unit_from_bits(h);
  }
  return o;
}

}  // namespace

double improved_noise(double x, double y, double z) {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const int X = int(std::fmod(fx, 256.0) + 256.0) & 255, Y = int(std::fmod(fy, 256.0) + 256.0) & 255,
            Z = int(std::fmod(fz, 256.0) + 256.0) & 255;
  x -= fx;
  y -= fy;
  z -= fz;
  const double u = fade(x), v = fade(y), w = fade(z);
  const auto& p = kP;
  const int A = p[std::size_t(X)] + Y, AA = p[std::size_t(A)] + Z, AB = p[std::size_t(A + 1)] + Z;
  const int B = p[std::size_t(X + 1)] + Y, BA = p[std::size_t(B)] + Z, BB = p[std::size_t(B + 1)] + Z;
  auto P = [&](int i) { return p[std::size_t(i)]; };
  return lerp(w,
              lerp(v, lerp(u, grad(P(AA), x, y, z), grad(P(BA), x - 1, y, z)),
                   lerp(u, grad(P(AB), x, y - 1, z), grad(P(BB), x - 1, y - 1, z))),
              lerp(v, lerp(u, grad(P(AA + 1), x, y, z - 1), grad(P(BA + 1), x - 1, y, z - 1)),
                   lerp(u, grad(P(AB + 1), x, y - 1, z - 1), grad(P(BB + 1), x - 1, y - 1, z - 1))));
}

double turbulence(double px, double py, double pz, const TurbulenceOptions& o) {
  double sum = 0, amplitude = 1, frequency = o.base_frequency;
  for (int k = 0; k < o.octaves; ++k) {
    const auto off = octave_offset(o.seed, k);
    double n = improved_noise(frequency * px + off[0], frequency * py + off[1], frequency * pz + off[2]);
    if (o.clip == NoiseClip::kPerOctave) n = std::clamp(n, 0.0, 1.0);
    sum += n * amplitude;
    amplitude /= o.gain;
    frequency *= o.lacunarity;
  }
  return o.clip == NoiseClip::kNone ? sum : std::clamp(sum, 0.0, 1.0);
}

namespace {

/// Seed 001's volumes: 8-bit node samples, z fastest (the layout of its files), unit spacing.
Volume generate_voxels(const VolumeGenerateOptions& o) {
  std::unique_ptr<VoxelSource> source;
  if (o.kind == VolumeKind::kShapes) {
    ShapesOptions so = o.shapes;
    so.dims = {o.nx, o.ny, o.nz};
    source = std::make_unique<ShapesVolume>(so);
  } else {
    source = std::make_unique<SkullPhantom>(std::array<int, 3>{o.nx, o.ny, o.nz}, o.shapes.seed);
  }
  if (o.nx < 2 || o.ny < 2 || o.nz < 2)
    throw InputError(fmt::format("volume generator: {} needs at least 2 voxels per axis", volume_kind_name(o.kind)));
  const std::int64_t n = checked_mul(checked_mul(o.nx, o.ny), o.nz);
  check_count("volume generator", "samples", n, input_limits().volume_samples, "volume_samples");
  auto storage = std::make_shared<std::vector<std::uint8_t>>(static_cast<std::size_t>(n));
  std::uint8_t* bytes = storage->data();
  // The same storage viewed z fastest: i = z + y nz + x ny nz.
  const std::int64_t sy = o.nz, sx = std::int64_t(o.ny) * o.nz;
  tbb::parallel_for(tbb::blocked_range<int>(0, o.nx), [&](const tbb::blocked_range<int>& r) {
    std::vector<VoxelCoord> c(std::size_t(o.nz));
    for (int x = r.begin(); x < r.end(); ++x)
      for (int y = 0; y < o.ny; ++y) {
        for (int z = 0; z < o.nz; ++z) c[std::size_t(z)] = VoxelCoord{x, y, z};
        source->fill(c.data(), c.size(), bytes + x * sx + y * sy);
      }
  });
  Volume v = Volume::wrap(storage, bytes, SampleType::kUint8, o.nx, o.ny, o.nz, sx, sy, 1);
  v.set_placement(SamplePlacement::kNodes);
  v.set_value_scale(1.0);
  return v;
}

}  // namespace

Volume generate_volume(const VolumeGenerateOptions& o) {
  if (o.kind == VolumeKind::kShapes || o.kind == VolumeKind::kSkull) return generate_voxels(o);
  if (o.kind == VolumeKind::kCtPhantom) {
    CtPhantomOptions ct = o.ct;
    ct.dims = {o.nx, o.ny, o.nz};
    return normalised_volume(generate_ct_phantom(ct), NormSource::kScanned, 0, 0, nullptr, "ct_phantom");
  }
  if (o.noise.octaves < 1 || o.noise.octaves > 16)
    throw InputError(fmt::format("volume generator: octaves must be in [1, 16] (got {})", o.noise.octaves));
  if (!(o.noise.gain > 0) || !(o.noise.lacunarity > 0) || !(o.noise.base_frequency > 0) ||
      !std::isfinite(o.noise.gain) || !std::isfinite(o.noise.lacunarity) || !std::isfinite(o.noise.base_frequency))
    throw InputError("volume generator: gain, lacunarity and base frequency must be finite and > 0");
  if (!std::isfinite(o.constant)) throw InputError("volume generator: the constant must be finite");
  Volume v = Volume::allocate(o.nx, o.ny, o.nz, o.storage, "volume generator");
  v.fit_to_box(Box3{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()});
  const double R = 0.5;
  tbb::parallel_for(tbb::blocked_range<int>(0, o.nz), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k < r.end(); ++k)
      for (int j = 0; j < o.ny; ++j)
        for (int i = 0; i < o.nx; ++i) {
          const double px = (i + 0.5) / o.nx, py = (j + 0.5) / o.ny, pz = (k + 0.5) / o.nz;
          double w = 0;
          if (o.kind == VolumeKind::kConstant) {
            w = o.constant;
          } else {
            const double rho =
                std::sqrt((px - 0.5) * (px - 0.5) + (py - 0.5) * (py - 0.5) + (pz - 0.5) * (pz - 0.5)) / R;
            const bool in_sphere = rho < 1.0;
            switch (o.kind) {
              case VolumeKind::kTurbulenceBox:
                w = turbulence(px, py, pz, o.noise);
                break;
              case VolumeKind::kTurbulenceSphere:
                if (in_sphere)
                  w = turbulence(px, py, pz, o.noise) * (o.falloff == SphereFalloff::kLinear ? 1.0 - rho : 1.0);
                break;
              case VolumeKind::kFireball:
                // Low density in the core, smoke thickening towards the rim, gone outside.
                if (in_sphere)
                  w = turbulence(px, py, pz, o.noise) * (0.15 + 0.85 * rho) * std::min(1.0, 8.0 * (1.0 - rho));
                break;
              case VolumeKind::kConstant:
              case VolumeKind::kShapes:
              case VolumeKind::kSkull:
              case VolumeKind::kCtPhantom:
                break;
            }
          }
          v.set_value(i, j, k, w);
        }
  });
  return v;
}

std::string volume_kind_name(VolumeKind kind) {
  switch (kind) {
    case VolumeKind::kTurbulenceBox:
      return "turbulence_box";
    case VolumeKind::kTurbulenceSphere:
      return "turbulence_sphere";
    case VolumeKind::kFireball:
      return "fireball";
    case VolumeKind::kConstant:
      return "constant";
    case VolumeKind::kShapes:
      return "shapes";
    case VolumeKind::kSkull:
      return "skull";
    case VolumeKind::kCtPhantom:
      return "ct_phantom";
  }
  return "turbulence_box";
}

VolumeKind parse_volume_kind(const std::string& name, const std::string& what) {
  for (VolumeKind k : {VolumeKind::kTurbulenceBox, VolumeKind::kTurbulenceSphere, VolumeKind::kFireball,
                       VolumeKind::kConstant, VolumeKind::kShapes, VolumeKind::kSkull, VolumeKind::kCtPhantom})
    if (volume_kind_name(k) == name) return k;
  throw InputError(
      fmt::format("{}: unknown volume kind '{}' (turbulence_box, turbulence_sphere, fireball, constant, shapes, skull, "
                  "ct_phantom)",
                  what, name));
}

std::string volume_content_hash(const Volume& v) {
  ContentHash h;
  h.add_field(fmt::format("{}x{}x{}:{}", v.nx(), v.ny(), v.nz(), sample_type_name(v.type())));
  const int bytes = sample_bytes(v.type());
  const auto* base = static_cast<const char*>(v.data());
  const auto st = v.strides();
  if (v.x_fastest_packed()) {
    h.add_bytes(std::string_view(base, std::size_t(v.sample_count()) * std::size_t(bytes)));
  } else {
    for (int k = 0; k < v.nz(); ++k)
      for (int j = 0; j < v.ny(); ++j)
        for (int i = 0; i < v.nx(); ++i)
          h.add_bytes(std::string_view(base + (i * st[0] + j * st[1] + k * st[2]) * bytes, std::size_t(bytes)));
  }
  return h.hex();
}

}  // namespace meltlab::render
