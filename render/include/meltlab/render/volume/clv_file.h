#pragma once
// Seed 001's volume file (spec ../shared/spec/cpu-large-volumes.md §2.1, §3.5 Table 3.1), which
// meltlab names NAME.clv (the source gives no extension): a 26-byte little-endian header and then
// 8-bit samples.
//
//   bytes 0-11   size x, y, z: three uint32 (clv.header.int_type)
//   bytes 12-23  cell shape x, y, z: three float32 (parsed and logged, not applied: the repo
//                ignores it, clv.cell_shape.apply)
//   byte 24      order: 1 = slices (linear, z fastest: i = z + y·N_z + x·N_y·N_z), 2 = blocks
//   byte 25      0 for linear; the block side B for blocks (bricked_volume.h)
//   samples      N_x N_y N_z bytes (linear) or n_b,x n_b,y n_b,z B³ bytes (blocked)
//
// e.g. 800³: 26 + 512 000 000 B linear, 26 + 644 972 544 B in 16³ blocks.
//
// Reading checks the header against the file's size before anything is mapped or allocated (a
// short file, a lying header, a wrong order byte, zero or overflowing dimensions are one-line
// InputErrors naming the file). A volume is read into RAM (a copy) or memory-mapped (read-only,
// shared by every thread: "Stream" in the source's tables), as the stored 8-bit numbers or
// converted to float32 at load (4x the memory). The samples are node samples with unit spacing
// at the origin and raw values (value_scale 1), as the source's renderer sees them.
//
// Writing: from a volume in memory, or streamed from a generator in file order (the source's
// "order generator" and "sample generator", §2.9): coordinates in batches of 32768, sampled in
// parallel, written in order (tbb::parallel_pipeline); batch 1 without threads is the source's
// first, naive writer (one write() per byte), kept to measure against.

#include <meltlab/render/volume/bricked_volume.h>
#include <meltlab/render/volume/volume.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace meltlab::render {

inline constexpr int kClvHeaderBytes = 26;

enum class ClvOrder : std::uint8_t { kLinear = 1, kBlocked = 2 };

struct ClvHeader {
  std::array<std::uint32_t, 3> dims{0, 0, 0};
  std::array<float, 3> cell_shape{1, 1, 1};
  ClvOrder order = ClvOrder::kLinear;
  int block_side = 0;  ///< blocks: B; linear: 0

  std::array<int, 3> int_dims() const { return {int(dims[0]), int(dims[1]), int(dims[2])}; }
  /// Sample bytes after the header (N³ or n_b³ B³); -1 on overflow.
  std::int64_t sample_bytes() const;
  /// The whole file: 26 + sample_bytes().
  std::int64_t file_bytes() const;
};

/// The 26 bytes of a header.
std::array<std::uint8_t, kClvHeaderBytes> encode_clv_header(const ClvHeader& h);
/// Decodes and checks a header (`what` names the file): order byte 1 or 2, byte 25 = 0 for
/// linear and in [2, 255] for blocks, dimensions in [2, 2^31) whose sample count fits the limits,
/// finite positive cell shape. Throws InputError.
ClvHeader decode_clv_header(const std::uint8_t* bytes, const std::string& what);
/// Reads and checks the header of a file, and the file's size against it.
ClvHeader read_clv_header(const std::filesystem::path& file);

/// clv.memory: how the samples are held.
enum class ClvMemory { kRam, kMmap };
/// What the renderer reads: the stored bytes, or float32 converted at load.
enum class ClvSamples { kStored, kFloat32 };

/// A volume read from a .clv file: exactly one of `linear` (a Volume viewing the z-fastest samples
/// in place: strides N_y N_z, N_z, 1) and `bricked` is set.
struct ClvVolume {
  ClvHeader header;
  Volume linear;
  BrickedVolume bricked;
  bool blocked() const { return !bricked.empty(); }
};

/// Opens a .clv file. Throws InputError naming the file.
ClvVolume open_clv(const std::filesystem::path& file, ClvMemory memory = ClvMemory::kMmap,
                   ClvSamples samples = ClvSamples::kStored);

/// Writes an 8-bit volume (its stored numbers) in either order, atomically. Throws InputError for
/// a volume that is not 8-bit or smaller than 2 voxels on an axis.
void write_clv(const std::filesystem::path& file, const Volume& volume, ClvOrder order, int block_side = 16);
void write_clv(const std::filesystem::path& file, const BrickedVolume& volume);

// ---- streamed generation (§2.9) ---------------------------------------------------------------

struct VoxelCoord {
  std::int32_t x, y, z;
};

/// The "sample generator": the value of any voxel, from any thread, in any order.
class VoxelSource {
 public:
  virtual ~VoxelSource() = default;
  virtual std::uint8_t value(int x, int y, int z) const = 0;
  /// out[i] = value(coords[i]) for a batch (a generator may cull its work by the batch's extent).
  /// Coordinates of block padding (outside the volume) may be passed to both; the writer zeroes
  /// their values, so a source need only not read past its storage for them.
  virtual void fill(const VoxelCoord* coords, std::size_t n, std::uint8_t* out) const;
};

/// The stored numbers of an 8-bit volume as a sample generator (InputError if it is not 8-bit);
/// the volume must outlive it.
std::unique_ptr<VoxelSource> voxels_of(const Volume& volume);

/// The "order generator": voxel coordinates in file order, batch by batch.
class VoxelOrder {
 public:
  VoxelOrder(const std::array<int, 3>& dims, ClvOrder order, int block_side);
  /// Up to `max` next coordinates into `out`; returns how many (0 at the end).
  std::size_t next(VoxelCoord* out, std::size_t max);
  std::int64_t total() const { return total_; }
  std::int64_t done() const { return done_; }

 private:
  std::array<int, 3> n_, nb_{1, 1, 1};
  ClvOrder order_;
  int side_ = 0;
  std::int64_t total_ = 0, done_ = 0;
  int c_[6] = {0, 0, 0, 0, 0, 0};  // position: linear (x, y, z) or blocks (bx, by, bz, lx, ly, lz)
};

struct ClvWriteOptions {
  ClvOrder order = ClvOrder::kLinear;
  int block_side = 16;
  std::int64_t batch = 32768;  ///< clv.gen.batch; 1 = the naive writer (one write() per sample, serial)
  bool parallel = true;        ///< sample each batch on the TBB threads
  Eigen::Vector3f cell_shape = Eigen::Vector3f::Ones();
  /// Called now and then from the writing thread with (samples written, total).
  std::function<void(std::int64_t, std::int64_t)> progress;
};

struct ClvWriteStats {
  double seconds = 0;
  std::int64_t bytes = 0;  ///< the whole file
  std::int64_t batches = 0;
  /// Linear order: how many voxels hold each value (the blocked order stores some voxels several
  /// times and pads; its histogram is left empty).
  std::vector<std::int64_t> histogram;
};

/// Streams a generated volume into a .clv file (atomically: a temporary file renamed when complete).
ClvWriteStats write_clv_generated(const std::filesystem::path& file, const std::array<int, 3>& dims,
                                  const VoxelSource& source, const ClvWriteOptions& options);

}  // namespace meltlab::render
