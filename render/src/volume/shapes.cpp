// Seed 001's synthetic volumes (see volume/shapes.h).

#include <meltlab/render/volume/shapes.h>

#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meltlab::render {

namespace {

std::uint64_t splitmix64(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

}  // namespace

Xoshiro256::Xoshiro256(std::uint64_t seed) {
  for (auto& s : s_) s = splitmix64(seed);
}

std::uint64_t Xoshiro256::next() {
  const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

std::int64_t Xoshiro256::uniform(std::int64_t lo, std::int64_t hi) {
  const std::uint64_t range = std::uint64_t(hi - lo) + 1;  // hi >= lo
  if (range == 0) return std::int64_t(next());             // the whole 64-bit range
  const std::uint64_t limit =
      std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % range;
  std::uint64_t x;
  do x = next();
  while (x >= limit);
  return lo + std::int64_t(x % range);
}

// ---- shapes ------------------------------------------------------------------------------------

ShapesVolume::ShapesVolume(const ShapesOptions& o) : o_(o) {
  if (o.count < 0) throw InputError(fmt::format("shapes: the shape count must be >= 0 (got {})", o.count));
  if (o.object_size < 1) throw InputError(fmt::format("shapes: the object size must be >= 1 (got {})", o.object_size));
  if (o.sample < 10 || o.sample > 245)
    throw InputError(fmt::format("shapes: the sample value must be in [10, 245] (values v0 ± 10; got {})", o.sample));
  const int s = o.object_size, spread = s / 3;
  for (int d : o.dims)
    if (s + spread > d)
      throw InputError(fmt::format("shapes: objects up to {} voxels (size {} + {}) do not fit a {} x {} x {} volume",
                                   s + spread, s, spread, o.dims[0], o.dims[1], o.dims[2]));
  Xoshiro256 rng(o.seed);
  shapes_.reserve(std::size_t(o.count));
  for (int i = 0; i < o.count; ++i) {
    Shape sh;
    sh.sphere = (rng.next() >> 63) != 0;
    for (int a = 0; a < 3; ++a) sh.size[std::size_t(a)] = int(rng.uniform(s - spread, s + spread));
    for (int a = 0; a < 3; ++a)
      sh.lo[std::size_t(a)] = int(rng.uniform(0, o.dims[std::size_t(a)] - sh.size[std::size_t(a)]));
    sh.value = std::uint8_t(rng.uniform(o.sample - 10, o.sample + 10));
    shapes_.push_back(sh);
  }
}

std::uint8_t ShapesVolume::value_of(const Shape& s, int x, int y, int z) {
  if (!s.sphere) return s.value;
  // |p - c|² <= r² with c = lo + size/2 and r = size_x / 2, in doubled integer coordinates (exact).
  const std::int64_t dx = 2 * std::int64_t(x) - (2 * std::int64_t(s.lo[0]) + s.size[0]);
  const std::int64_t dy = 2 * std::int64_t(y) - (2 * std::int64_t(s.lo[1]) + s.size[1]);
  const std::int64_t dz = 2 * std::int64_t(z) - (2 * std::int64_t(s.lo[2]) + s.size[2]);
  return dx * dx + dy * dy + dz * dz <= std::int64_t(s.size[0]) * s.size[0] ? s.value : 0;
}

std::uint8_t ShapesVolume::value(int x, int y, int z) const {
  for (const Shape& s : shapes_)
    if (x >= s.lo[0] && x < s.lo[0] + s.size[0] && y >= s.lo[1] && y < s.lo[1] + s.size[1] && z >= s.lo[2] &&
        z < s.lo[2] + s.size[2])
      return value_of(s, x, y, z);
  return 0;
}

void ShapesVolume::fill(const VoxelCoord* c, std::size_t n, std::uint8_t* out) const {
  if (n == 0) return;
  int lo[3] = {c[0].x, c[0].y, c[0].z}, hi[3] = {c[0].x, c[0].y, c[0].z};
  for (std::size_t i = 1; i < n; ++i) {
    lo[0] = std::min(lo[0], c[i].x), hi[0] = std::max(hi[0], c[i].x);
    lo[1] = std::min(lo[1], c[i].y), hi[1] = std::max(hi[1], c[i].y);
    lo[2] = std::min(lo[2], c[i].z), hi[2] = std::max(hi[2], c[i].z);
  }
  // The shapes whose box meets the batch's, in list order (the rule's order).
  std::vector<const Shape*> near;
  for (const Shape& s : shapes_) {
    bool meets = true;
    for (int a = 0; a < 3; ++a)
      meets = meets && s.lo[std::size_t(a)] <= hi[a] && s.lo[std::size_t(a)] + s.size[std::size_t(a)] > lo[a];
    if (meets) near.push_back(&s);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const int x = c[i].x, y = c[i].y, z = c[i].z;
    std::uint8_t v = 0;
    for (const Shape* s : near)
      if (x >= s->lo[0] && x < s->lo[0] + s->size[0] && y >= s->lo[1] && y < s->lo[1] + s->size[1] && z >= s->lo[2] &&
          z < s->lo[2] + s->size[2]) {
        v = value_of(*s, x, y, z);
        break;
      }
    out[i] = v;
  }
}

// ---- the skull phantom -------------------------------------------------------------------------

SkullPhantom::SkullPhantom(const std::array<int, 3>& dims, std::uint64_t seed) : n_(dims), seed_(seed) {
  for (int d : dims)
    if (d < 2) throw InputError("skull phantom: at least 2 voxels per axis");
}

std::uint8_t SkullPhantom::value(int x, int y, int z) const {
  // Noise in [-1, 1] from a hash of the voxel and the seed (the same value from any thread).
  std::uint64_t h = seed_ ^ (std::uint64_t(x) * 0x9E3779B97F4A7C15ull) ^ (std::uint64_t(y) * 0xC2B2AE3D27D4EB4Full) ^
                    (std::uint64_t(z) * 0x165667B19E3779F9ull);
  const double noise = double(splitmix64(h) >> 11) * (2.0 / 9007199254740992.0) - 1.0;
  // Head frame: centred in x, y; the slab is the middle of a head 1.1 x as tall as it is long.
  const double sx = 0.5 * n_[0], sy = 0.5 * n_[1];
  const double ax = 0.40 * n_[0], ay = 0.47 * n_[1], az = 0.52 * n_[1];
  const double px = x - sx + 0.5, py = y - sy + 0.5, pz = (z - 0.5 * n_[2] + 0.5);
  const double r = std::sqrt((px / ax) * (px / ax) + (py / ay) * (py / ay) + (pz / az) * (pz / az));
  const double depth = (1.0 - r) * std::min(ax, ay);  // approximate distance in from the surface (voxels)
  auto clamp8 = [](double v) { return std::uint8_t(std::clamp(std::lround(v), 0l, 255l)); };
  if (depth < 0) return clamp8(6 + 6 * noise);  // air
  // Eye orbits and a frontal sinus: holes through the front of the skull (+y).
  auto ball = [&](double cx, double cy, double cz, double rad) {
    const double dx = px - cx, dy = py - cy, dz = pz - cz;
    return dx * dx + dy * dy + dz * dz <= rad * rad;
  };
  const double orbit_r = 0.09 * n_[0];
  if (ball(-0.16 * n_[0], 0.38 * n_[1], 0, orbit_r) || ball(0.16 * n_[0], 0.38 * n_[1], 0, orbit_r))
    return clamp8(18 + 4 * noise);                                                      // orbital fat
  if (ball(0, 0.42 * n_[1], 0.12 * n_[2], 0.05 * n_[0])) return clamp8(5 + 4 * noise);  // sinus air
  const double t = 0.025 * std::min(ax, ay) * 2.0;       // layer unit (about 5 voxels for 256²)
  if (depth < 1.2 * t) return clamp8(25 + 5 * noise);    // scalp
  if (depth < 1.8 * t) return clamp8(200 + 15 * noise);  // outer table
  if (depth < 2.6 * t) return clamp8(120 + 20 * noise);  // diploë
  if (depth < 3.2 * t) return clamp8(200 + 15 * noise);  // inner table
  // Ventricles.
  if (ball(-0.06 * n_[0], 0.02 * n_[1], 0, 0.07 * n_[0]) || ball(0.06 * n_[0], 0.02 * n_[1], 0, 0.07 * n_[0]))
    return clamp8(12 + 3 * noise);
  return clamp8(30 + 6 * noise);  // brain
}

}  // namespace meltlab::render
