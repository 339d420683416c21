// Seed 001's volume file (see volume/clv_file.h).

#include <meltlab/render/volume/clv_file.h>

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>
#include <meltlab/core/mapped_file.h>

#include <fcntl.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <vector>

namespace meltlab::render {

namespace fs = std::filesystem;

static_assert(std::endian::native == std::endian::little, "the .clv header is read as little-endian");

std::int64_t ClvHeader::sample_bytes() const {
  const auto d = int_dims();
  if (order == ClvOrder::kBlocked) return BrickedVolume::stored_samples(d, block_side);
  return checked_mul(checked_mul(d[0], d[1]), d[2]);
}

std::int64_t ClvHeader::file_bytes() const {
  const std::int64_t s = sample_bytes();
  return s < 0 ? -1 : s + kClvHeaderBytes;
}

std::array<std::uint8_t, kClvHeaderBytes> encode_clv_header(const ClvHeader& h) {
  std::array<std::uint8_t, kClvHeaderBytes> b{};
  std::memcpy(b.data(), h.dims.data(), 12);
  std::memcpy(b.data() + 12, h.cell_shape.data(), 12);
  b[24] = static_cast<std::uint8_t>(h.order);
  b[25] = static_cast<std::uint8_t>(h.order == ClvOrder::kBlocked ? h.block_side : 0);
  return b;
}

ClvHeader decode_clv_header(const std::uint8_t* b, const std::string& what) {
  ClvHeader h;
  std::memcpy(h.dims.data(), b, 12);
  std::memcpy(h.cell_shape.data(), b + 12, 12);
  const int order = b[24], side = b[25];
  if (order != 1 && order != 2)
    throw InputError(fmt::format("{}: header byte 24 (order) is {}; it must be 1 (slices) or 2 (blocks)", what, order));
  h.order = static_cast<ClvOrder>(order);
  if (h.order == ClvOrder::kLinear && side != 0)
    throw InputError(fmt::format("{}: header byte 25 is {}; it must be 0 for the linear order", what, side));
  if (h.order == ClvOrder::kBlocked && side < 2)
    throw InputError(
        fmt::format("{}: header byte 25 (block side) is {}; blocks need a side of at least 2", what, side));
  h.block_side = h.order == ClvOrder::kBlocked ? side : 0;
  for (std::uint32_t d : h.dims)
    if (d < 2 || d > 2147483647u)
      throw InputError(fmt::format("{}: the header's size {} x {} x {} is invalid (each in [2, 2^31 - 1] voxels)", what,
                                   h.dims[0], h.dims[1], h.dims[2]));
  for (float c : h.cell_shape)
    if (!(std::isfinite(c) && c > 0))
      throw InputError(fmt::format("{}: the header's cell shape ({}, {}, {}) must be finite and positive", what,
                                   h.cell_shape[0], h.cell_shape[1], h.cell_shape[2]));
  const auto d = h.int_dims();
  const std::int64_t voxels = checked_mul(checked_mul(d[0], d[1]), d[2]);
  if (voxels < 0 || h.sample_bytes() < 0)
    throw InputError(fmt::format("{}: the header's size {} x {} x {} overflows", what, d[0], d[1], d[2]));
  check_count(what, "voxels", voxels, input_limits().volume_samples, "volume_samples");
  return h;
}

ClvHeader read_clv_header(const fs::path& file) {
  const std::int64_t size = check_input_file(file, "volume (.clv)");
  if (size < kClvHeaderBytes)
    throw InputError(fmt::format("{}: {} bytes, shorter than the 26-byte .clv header", file.string(), size));
  std::array<std::uint8_t, kClvHeaderBytes> b{};
  {
    std::ifstream in(file, std::ios::binary);
    in.read(reinterpret_cast<char*>(b.data()), kClvHeaderBytes);
    if (in.gcount() != kClvHeaderBytes) throw InputError(fmt::format("{}: cannot read the header", file.string()));
  }
  const ClvHeader h = decode_clv_header(b.data(), file.string());
  if (size != h.file_bytes()) {
    const auto d = h.int_dims();
    throw InputError(fmt::format(
        "{}: holds {} bytes, but its header declares {} x {} x {} voxels {} = {} + {} bytes", file.string(), size, d[0],
        d[1], d[2],
        h.order == ClvOrder::kBlocked ? fmt::format("in blocks of {}³", h.block_side) : std::string("in slices"),
        kClvHeaderBytes, h.sample_bytes()));
  }
  return h;
}

namespace {

/// The samples as float32 (values × 1: the stored numbers), same order.
std::shared_ptr<std::vector<float>> to_float(const std::uint8_t* src, std::int64_t n) {
  auto out = std::make_shared<std::vector<float>>(static_cast<std::size_t>(n));
  float* dst = out->data();
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, n, 1 << 16), [&](const auto& r) {
    for (std::int64_t i = r.begin(); i < r.end(); ++i) dst[i] = float(src[i]);
  });
  return out;
}

}  // namespace

ClvVolume open_clv(const fs::path& file, ClvMemory memory, ClvSamples samples) {
  ClvVolume out;
  out.header = read_clv_header(file);
  const std::int64_t n = out.header.sample_bytes();
  std::shared_ptr<const void> owner;
  const std::uint8_t* bytes = nullptr;
  if (memory == ClvMemory::kMmap) {
    auto map = MappedFile::open(file, "volume (.clv)");
    if (map->size() != out.header.file_bytes())
      throw InputError(fmt::format("{}: the file changed while it was opened", file.string()));
    bytes = map->data() + kClvHeaderBytes;
    owner = map;
  } else {
    auto buffer = std::make_shared<std::vector<std::uint8_t>>(static_cast<std::size_t>(n));
    std::ifstream in(file, std::ios::binary);
    in.seekg(kClvHeaderBytes);
    in.read(reinterpret_cast<char*>(buffer->data()), std::streamsize(n));
    if (in.gcount() != std::streamsize(n))
      throw InputError(fmt::format("{}: read error (the file changed while it was read?)", file.string()));
    bytes = buffer->data();
    owner = buffer;
  }
  const void* data = bytes;
  SampleType type = SampleType::kUint8;
  if (samples == ClvSamples::kFloat32) {
    auto f = to_float(bytes, n);
    data = f->data();
    owner = f;  // the float copy; a map or buffer of bytes is released
    type = SampleType::kFloat32;
  }
  const auto d = out.header.int_dims();
  if (out.header.order == ClvOrder::kBlocked) {
    out.bricked = BrickedVolume::wrap(owner, data, type, d, out.header.block_side);
    out.bricked.set_placement(SamplePlacement::kNodes);
    out.bricked.set_value_scale(1.0);
  } else {
    // z fastest: i = z + y N_z + x N_y N_z (clv.layout.linear_order).
    out.linear = Volume::wrap(owner, data, type, d[0], d[1], d[2], std::int64_t(d[1]) * d[2], d[2], 1);
    out.linear.set_placement(SamplePlacement::kNodes);
    out.linear.set_value_scale(1.0);
  }
  return out;
}

// ---- writing ---------------------------------------------------------------------------------

void VoxelSource::fill(const VoxelCoord* coords, std::size_t n, std::uint8_t* out) const {
  for (std::size_t i = 0; i < n; ++i) out[i] = value(coords[i].x, coords[i].y, coords[i].z);
}

VoxelOrder::VoxelOrder(const std::array<int, 3>& dims, ClvOrder order, int block_side)
    : n_(dims), order_(order), side_(block_side) {
  if (order == ClvOrder::kBlocked) {
    for (int a = 0; a < 3; ++a) nb_[std::size_t(a)] = BrickedVolume::blocks_per_axis(dims[std::size_t(a)], side_);
    total_ = BrickedVolume::stored_samples(dims, side_);
  } else {
    total_ = std::int64_t(dims[0]) * dims[1] * dims[2];
  }
}

std::size_t VoxelOrder::next(VoxelCoord* out, std::size_t max) {
  std::size_t k = 0;
  if (order_ == ClvOrder::kLinear) {
    int& x = c_[0];
    int& y = c_[1];
    int& z = c_[2];
    while (k < max && done_ < total_) {
      out[k++] = VoxelCoord{x, y, z};
      ++done_;
      if (++z == n_[2]) {
        z = 0;
        if (++y == n_[1]) y = 0, ++x;
      }
    }
  } else {
    const int S = side_, st = side_ - 1;
    while (k < max && done_ < total_) {
      out[k++] = VoxelCoord{c_[0] * st + c_[3], c_[1] * st + c_[4], c_[2] * st + c_[5]};
      ++done_;
      if (++c_[5] == S) {
        c_[5] = 0;
        if (++c_[4] == S) {
          c_[4] = 0;
          if (++c_[3] == S) {
            c_[3] = 0;
            if (++c_[2] == nb_[2]) {
              c_[2] = 0;
              if (++c_[1] == nb_[1]) c_[1] = 0, ++c_[0];
            }
          }
        }
      }
    }
  }
  return k;
}

namespace {

void write_all(int fd, const void* data, std::size_t n, const fs::path& file) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      throw InputError(fmt::format("{}: write error: {} (disk full?)", file.string(), std::strerror(errno)));
    }
    p += w;
    n -= std::size_t(w);
  }
}

/// Block padding reaches past the volume (the writer zeroes it); stored samples end at the volume.
bool padding(const std::array<int, 3>& n, int x, int y, int z) { return x >= n[0] || y >= n[1] || z >= n[2]; }

class VolumeVoxels final : public VoxelSource {
 public:
  explicit VolumeVoxels(const Volume& v) : v_(v) {}
  std::uint8_t value(int x, int y, int z) const override {
    if (padding(n_, x, y, z)) return 0;
    return static_cast<const std::uint8_t*>(v_.data())[x * st_[0] + y * st_[1] + z * st_[2]];
  }

 private:
  const Volume& v_;
  std::array<std::int64_t, 3> st_ = v_.strides();
  std::array<int, 3> n_ = v_.dims();
};

class BrickVoxels final : public VoxelSource {
 public:
  explicit BrickVoxels(const BrickedVolume& v) : s_(v.samples<std::uint8_t>()), n_(v.dims()) {}
  std::uint8_t value(int x, int y, int z) const override { return padding(n_, x, y, z) ? 0 : s_.stored(x, y, z); }

 private:
  BrickSamples<std::uint8_t> s_;
  std::array<int, 3> n_;
};

}  // namespace

ClvWriteStats write_clv_generated(const fs::path& file, const std::array<int, 3>& dims, const VoxelSource& source,
                                  const ClvWriteOptions& o) {
  ClvHeader h;
  for (int a = 0; a < 3; ++a) {
    if (dims[std::size_t(a)] < 2)
      throw InputError(fmt::format("{}: a .clv volume needs at least 2 voxels per axis", file.string()));
    h.dims[std::size_t(a)] = std::uint32_t(dims[std::size_t(a)]);
    h.cell_shape[std::size_t(a)] = o.cell_shape[a];
  }
  h.order = o.order;
  h.block_side = o.order == ClvOrder::kBlocked ? o.block_side : 0;
  if (o.order == ClvOrder::kBlocked && (o.block_side < 2 || o.block_side > 255))
    throw InputError(fmt::format("{}: the block side must be in [2, 255] (got {})", file.string(), o.block_side));
  if (o.batch < 1) throw InputError("the generator's batch must be >= 1 sample");
  const auto header = encode_clv_header(h);
  (void)decode_clv_header(header.data(), file.string());  // the same checks as a reader's
  ClvWriteStats stats;
  const bool count = o.order == ClvOrder::kLinear;
  if (count) stats.histogram.assign(256, 0);
  const auto t0 = std::chrono::steady_clock::now();
  write_atomically(file, [&](const fs::path& tmp) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw InputError(fmt::format("{}: cannot create: {}", file.string(), std::strerror(errno)));
    try {
      write_all(fd, header.data(), header.size(), file);
      VoxelOrder order(dims, o.order, h.block_side);
      const int nx = dims[0], ny = dims[1], nz = dims[2];
      auto outside = [&](const VoxelCoord& c) { return c.x >= nx || c.y >= ny || c.z >= nz; };
      if (o.batch == 1 && !o.parallel) {
        // The naive writer: one sample, one write().
        VoxelCoord c{};
        while (order.next(&c, 1)) {
          const std::uint8_t v = outside(c) ? 0 : source.value(c.x, c.y, c.z);
          write_all(fd, &v, 1, file);
          if (count) ++stats.histogram[v];
          ++stats.batches;
          if (o.progress && (order.done() & 0xFFFFF) == 0) o.progress(order.done(), order.total());
        }
      } else {
        struct Batch {
          std::vector<VoxelCoord> coords;
          std::vector<std::uint8_t> values;
          std::size_t n = 0;
        };
        const std::size_t batch = std::size_t(o.batch);
        const std::size_t tokens = o.parallel ? 8 : 1;
        std::vector<Batch> pool(tokens);
        for (auto& b : pool) b.coords.resize(batch), b.values.resize(batch);
        std::size_t next_token = 0;
        tbb::parallel_pipeline(tokens,
                               tbb::make_filter<void, Batch*>(tbb::filter_mode::serial_in_order,
                                                              [&](tbb::flow_control& fc) -> Batch* {
                                                                Batch* b = &pool[next_token++ % tokens];
                                                                b->n = order.next(b->coords.data(), batch);
                                                                if (b->n == 0) {
                                                                  fc.stop();
                                                                  return nullptr;
                                                                }
                                                                return b;
                                                              }) &
                                   tbb::make_filter<Batch*, Batch*>(
                                       o.parallel ? tbb::filter_mode::parallel : tbb::filter_mode::serial_in_order,
                                       [&](Batch* b) {
                                         source.fill(b->coords.data(), b->n, b->values.data());
                                         if (o.order == ClvOrder::kBlocked)  // clv.layout.block_pad_value = 0
                                           for (std::size_t i = 0; i < b->n; ++i)
                                             if (outside(b->coords[i])) b->values[i] = 0;
                                         return b;
                                       }) &
                                   tbb::make_filter<Batch*, void>(tbb::filter_mode::serial_in_order, [&](Batch* b) {
                                     write_all(fd, b->values.data(), b->n, file);
                                     if (count)
                                       for (std::size_t i = 0; i < b->n; ++i) ++stats.histogram[b->values[i]];
                                     ++stats.batches;
                                     if (o.progress) o.progress(order.done(), order.total());
                                   }));
      }
    } catch (...) {
      ::close(fd);
      throw;
    }
    if (::close(fd) != 0) throw InputError(fmt::format("{}: write error: {}", file.string(), std::strerror(errno)));
  });
  stats.bytes = h.file_bytes();
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

std::unique_ptr<VoxelSource> voxels_of(const Volume& v) {
  if (v.type() != SampleType::kUint8)
    throw InputError(fmt::format("a .clv file holds 8-bit samples (the volume is {})", sample_type_name(v.type())));
  return std::make_unique<VolumeVoxels>(v);
}

void write_clv(const fs::path& file, const Volume& v, ClvOrder order, int block_side) {
  if (v.type() != SampleType::kUint8)
    throw InputError(fmt::format("{}: a .clv file holds 8-bit samples (the volume is {})", file.string(),
                                 sample_type_name(v.type())));
  ClvWriteOptions o;
  o.order = order;
  o.block_side = block_side;
  write_clv_generated(file, v.dims(), VolumeVoxels(v), o);
}

void write_clv(const fs::path& file, const BrickedVolume& v) {
  if (v.type() != SampleType::kUint8)
    throw InputError(fmt::format("{}: a .clv file holds 8-bit samples (the volume is {})", file.string(),
                                 sample_type_name(v.type())));
  ClvWriteOptions o;
  o.order = ClvOrder::kBlocked;
  o.block_side = v.side();
  write_clv_generated(file, v.dims(), BrickVoxels(v), o);
}

}  // namespace meltlab::render
