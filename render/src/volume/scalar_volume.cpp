// Medical volume samples as stored, and their normalisation (see volume/scalar_volume.h).

#include <meltlab/render/volume/scalar_volume.h>

#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace meltlab::render {

static_assert(std::endian::native == std::endian::little, "scalar volumes are held little-endian");

int scalar_bytes(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUint8:
      return 1;
    case ScalarType::kInt16:
    case ScalarType::kUint16:
      return 2;
    case ScalarType::kInt32:
    case ScalarType::kUint32:
    case ScalarType::kFloat32:
      return 4;
    case ScalarType::kFloat64:
      return 8;
  }
  return 1;
}

std::string scalar_type_name(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
      return "int8";
    case ScalarType::kUint8:
      return "uint8";
    case ScalarType::kInt16:
      return "int16";
    case ScalarType::kUint16:
      return "uint16";
    case ScalarType::kInt32:
      return "int32";
    case ScalarType::kUint32:
      return "uint32";
    case ScalarType::kFloat32:
      return "float";
    case ScalarType::kFloat64:
      return "double";
  }
  return "?";
}

std::optional<ScalarType> parse_scalar_type(const std::string& name) {
  for (ScalarType t : {ScalarType::kInt8, ScalarType::kUint8, ScalarType::kInt16, ScalarType::kUint16,
                       ScalarType::kInt32, ScalarType::kUint32, ScalarType::kFloat32, ScalarType::kFloat64})
    if (name == scalar_type_name(t)) return t;
  if (name == "float32") return ScalarType::kFloat32;
  if (name == "float64") return ScalarType::kFloat64;
  return std::nullopt;
}

namespace {

template <class T>
T load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

/// Calls fn(T{}) with the C++ type of a scalar type.
template <class Fn>
decltype(auto) visit_type(ScalarType type, Fn&& fn) {
  switch (type) {
    case ScalarType::kInt8:
      return fn(std::int8_t{});
    case ScalarType::kUint8:
      return fn(std::uint8_t{});
    case ScalarType::kInt16:
      return fn(std::int16_t{});
    case ScalarType::kUint16:
      return fn(std::uint16_t{});
    case ScalarType::kInt32:
      return fn(std::int32_t{});
    case ScalarType::kUint32:
      return fn(std::uint32_t{});
    case ScalarType::kFloat32:
      return fn(float{});
    case ScalarType::kFloat64:
      break;
  }
  return fn(double{});
}

}  // namespace

ScalarVolume ScalarVolume::allocate(const std::array<int, 3>& dims, ScalarType type, const std::string& what) {
  for (int d : dims)
    if (d < 1)
      throw InputError(fmt::format("{}: dimensions {} x {} x {} must be >= 1", what, dims[0], dims[1], dims[2]));
  const std::int64_t count = checked_mul(checked_mul(dims[0], dims[1]), dims[2]);
  if (count < 0) throw InputError(fmt::format("{}: dimensions {} x {} x {} overflow", what, dims[0], dims[1], dims[2]));
  check_count(what, "volume samples", count, input_limits().volume_samples, "volume_samples");
  ScalarVolume v;
  v.dims = dims;
  v.type = type;
  v.bytes.assign(std::size_t(count) * std::size_t(scalar_bytes(type)), 0);
  return v;
}

double ScalarVolume::value(std::int64_t n) const {
  const std::uint8_t* p = bytes.data() + n * scalar_bytes(type);
  return visit_type(type, [&](auto t) { return static_cast<double>(load<decltype(t)>(p)); });
}

void ScalarVolume::set_value(std::int64_t n, double v) {
  std::uint8_t* p = bytes.data() + n * scalar_bytes(type);
  visit_type(type, [&](auto t) {
    using T = decltype(t);
    T x;
    if constexpr (std::is_floating_point_v<T>) {
      x = static_cast<T>(v);
    } else {
      const double r = std::round(v);
      x = r <= double(std::numeric_limits<T>::lowest()) ? std::numeric_limits<T>::lowest()
          : r >= double(std::numeric_limits<T>::max())  ? std::numeric_limits<T>::max()
                                                        : static_cast<T>(r);
    }
    std::memcpy(p, &x, sizeof(T));
  });
}

std::array<double, 2> ScalarVolume::scanned_range() const {
  using Range = std::array<double, 2>;
  const Range empty{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  const Range r = visit_type(type, [&](auto t) {
    using T = decltype(t);
    const std::uint8_t* base = bytes.data();
    return tbb::parallel_reduce(
        tbb::blocked_range<std::int64_t>(0, sample_count(), 1 << 16), empty,
        [&](const auto& rng, Range acc) {
          for (std::int64_t n = rng.begin(); n < rng.end(); ++n) {
            const double x = static_cast<double>(load<T>(base + n * std::int64_t(sizeof(T))));
            if (x < acc[0]) acc[0] = x;  // NaN compares false both ways: ignored
            if (x > acc[1]) acc[1] = x;
          }
          return acc;
        },
        [](const Range& a, const Range& b) {
          return Range{std::min(a[0], b[0]), std::max(a[1], b[1])};
        });
  });
  if (!(r[0] <= r[1])) return {0, 0};
  return r;
}

void swap_sample_bytes(std::vector<std::uint8_t>& bytes, ScalarType type) {
  const std::size_t w = std::size_t(scalar_bytes(type));
  if (w == 1) return;
  for (std::size_t i = 0; i + w <= bytes.size(); i += w)
    std::reverse(bytes.begin() + std::ptrdiff_t(i), bytes.begin() + std::ptrdiff_t(i + w));
}

void check_finite_samples(const ScalarVolume& v, const std::string& what) {
  if (v.type != ScalarType::kFloat32 && v.type != ScalarType::kFloat64) return;
  for (std::int64_t n = 0; n < v.sample_count(); ++n)
    if (!std::isfinite(v.value(n)))
      throw InputError(fmt::format("{}: sample {} is not a finite number ({})", what, n, v.value(n)));
}

std::string scalar_content_hash(const ScalarVolume& v) {
  ContentHash h;
  h.add_field(fmt::format("{}x{}x{}:{}", v.dims[0], v.dims[1], v.dims[2], scalar_type_name(v.type)));
  h.add_bytes(std::string_view(reinterpret_cast<const char*>(v.bytes.data()), v.bytes.size()));
  return h.hex();
}

std::string norm_source_name(NormSource s) {
  switch (s) {
    case NormSource::kScanned:
      return "scanned";
    case NormSource::kHeader:
      return "header";
    case NormSource::kWindow:
      return "window";
    case NormSource::kNone:
      break;
  }
  return "none";
}

std::string Normalisation::describe() const {
  if (source == NormSource::kNone)
    return fmt::format("none (stored values; scanned range [{:.9g}, {:.9g}])", scanned_min, scanned_max);
  return fmt::format(
      "{} [{:.9g}, {:.9g}] -> [0, 1]{} (scanned range [{:.9g}, {:.9g}]; {} samples clipped low, {} high)",
      norm_source_name(source), lo, hi, constant ? " (constant: every sample 0)" : "", scanned_min, scanned_max,
      clipped_low, clipped_high);
}

Volume normalised_volume(const ScalarVolume& sv, NormSource source, double lo, double hi, Normalisation* info,
                         const std::string& what) {
  Normalisation n;
  n.source = source;
  const auto scanned = sv.scanned_range();
  n.scanned_min = scanned[0];
  n.scanned_max = scanned[1];
  if (source == NormSource::kScanned) {
    lo = scanned[0];
    hi = scanned[1];
  }
  if (source != NormSource::kNone && !(std::isfinite(lo) && std::isfinite(hi) && lo <= hi))
    throw InputError(fmt::format("{}: the {} range [{}, {}] cannot be normalised (it needs finite lo <= hi)", what,
                                 norm_source_name(source), lo, hi));
  n.lo = lo;
  n.hi = hi;
  n.constant = source != NormSource::kNone && lo == hi;
  Volume v = Volume::allocate(sv.dims[0], sv.dims[1], sv.dims[2], SampleType::kFloat32, what);
  float* out = static_cast<float*>(v.mutable_data());
  const double span = hi - lo;
  std::int64_t low = 0, high = 0;
  visit_type(sv.type, [&](auto t) {
    using T = decltype(t);
    const std::uint8_t* base = sv.bytes.data();
    using Counts = std::array<std::int64_t, 2>;
    const Counts c = tbb::parallel_reduce(
        tbb::blocked_range<std::int64_t>(0, sv.sample_count(), 1 << 16), Counts{0, 0},
        [&](const auto& rng, Counts acc) {
          for (std::int64_t i = rng.begin(); i < rng.end(); ++i) {
            const double f = static_cast<double>(load<T>(base + i * std::int64_t(sizeof(T))));
            double r;
            if (source == NormSource::kNone) {
              r = f;
            } else if (n.constant) {
              r = 0;
            } else {
              r = (f - lo) / span;
              if (r < 0) ++acc[0], r = 0;
              if (r > 1) ++acc[1], r = 1;
            }
            out[i] = static_cast<float>(r);
          }
          return acc;
        },
        [](const Counts& a, const Counts& b) {
          return Counts{a[0] + b[0], a[1] + b[1]};
        });
    low = c[0];
    high = c[1];
  });
  n.clipped_low = low;
  n.clipped_high = high;
  v.set_placement(SamplePlacement::kNodes);
  v.set_spacing(sv.spacing);
  v.set_origin(sv.origin);
  v.set_value_scale(1.0);
  spdlog::debug("{}: vsi.data.norm_source = {}", what, n.describe());  // recorded by callers (info, render.json)
  if (info) *info = n;
  return v;
}

ScalarVolume scalar_volume_of(const Volume& v) {
  const ScalarType t = v.type() == SampleType::kUint8    ? ScalarType::kUint8
                       : v.type() == SampleType::kUint16 ? ScalarType::kUint16
                                                         : ScalarType::kFloat32;
  ScalarVolume s = ScalarVolume::allocate(v.dims(), t);
  s.spacing = v.spacing();
  s.origin = v.origin();
  const int w = scalar_bytes(t);
  const auto* base = static_cast<const std::uint8_t*>(v.data());
  const auto st = v.strides();
  std::int64_t n = 0;
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i, ++n)
        std::memcpy(s.bytes.data() + n * w, base + (i * st[0] + j * st[1] + k * st[2]) * w, std::size_t(w));
  return s;
}

}  // namespace meltlab::render
