// Seed 001's storage (render/volume/clv_file.h, bricked_volume.h, shapes.h, transfer_function.h):
// the file-size arithmetic of spec §2.1/§3, round trips of both orders in RAM and memory-mapped,
// the blocked layout's geometry, the streamed (batched, parallel) writer against the naive one,
// the shapes generator against its rule, and the bad files of the issue (short, lying header,
// wrong order byte, zero dimensions, dimensions whose product overflows) refused before any read.

#include <meltlab/core/error.h>
#include <meltlab/core/mapped_file.h>
#include <meltlab/render/volume/bricked_volume.h>
#include <meltlab/render/volume/clv_file.h>
#include <meltlab/render/volume/generate.h>
#include <meltlab/render/volume/shapes.h>
#include <meltlab/render/volume/transfer_function.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <set>

#include "test_files.h"

namespace meltlab::render {
namespace {

using test::message_of;
using test::TempFolder;
using ::testing::HasSubstr;

std::string bytes_of(const std::filesystem::path& f) {
  std::ifstream in(f, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::filesystem::path& f, const std::string& b) {
  std::ofstream out(f, std::ios::binary);
  out.write(b.data(), std::streamsize(b.size()));
}

std::string header_bytes(std::uint32_t nx, std::uint32_t ny, std::uint32_t nz, int order, int side,
                         float shape = 1.0f) {
  std::string h(26, '\0');
  const std::uint32_t d[3] = {nx, ny, nz};
  const float c[3] = {shape, shape, shape};
  std::memcpy(h.data(), d, 12);
  std::memcpy(h.data() + 12, c, 12);
  h[24] = char(order);
  h[25] = char(side);
  return h;
}

/// A small shapes volume (z fastest, 8-bit) of the seed's kind.
Volume small_shapes(int nx, int ny, int nz, int count = 12, int size = 9, std::uint64_t seed = 5) {
  VolumeGenerateOptions g;
  g.kind = VolumeKind::kShapes;
  g.nx = nx, g.ny = ny, g.nz = nz;
  g.shapes.count = count;
  g.shapes.object_size = size;
  g.shapes.seed = seed;
  return generate_volume(g);
}

// ---- arithmetic ---------------------------------------------------------------------------------

TEST(ClvFile, FileSizesMatchTheSpecsArithmetic) {
  // §3: n_b = ceil(799/15) = 54, 54³ · 16³ = 644 972 544; ceil(1999/15) = 134, 134³ · 4096 = 9 855 401 984.
  EXPECT_EQ(BrickedVolume::blocks_per_axis(800, 16), 54);
  EXPECT_EQ(BrickedVolume::blocks_per_axis(2000, 16), 134);
  EXPECT_EQ(BrickedVolume::stored_samples({800, 800, 800}, 16), 644972544);
  EXPECT_EQ(BrickedVolume::stored_samples({2000, 2000, 2000}, 16), 9855401984);
  ClvHeader h;
  h.dims = {800, 800, 800};
  EXPECT_EQ(h.file_bytes(), 26 + 512000000);
  h.order = ClvOrder::kBlocked;
  h.block_side = 16;
  EXPECT_EQ(h.file_bytes(), 26 + 644972544);
  // Exactly one block when N - 1 = B - 1; two when one voxel more.
  EXPECT_EQ(BrickedVolume::blocks_per_axis(16, 16), 1);
  EXPECT_EQ(BrickedVolume::blocks_per_axis(17, 16), 2);
}

TEST(ClvFile, HeaderRoundTripsAndIsLittleEndianAsTable31) {
  ClvHeader h;
  h.dims = {3, 70000, 5};
  h.cell_shape = {1.5f, 2.0f, 0.25f};
  h.order = ClvOrder::kBlocked;
  h.block_side = 7;
  const auto b = encode_clv_header(h);
  EXPECT_EQ(b[0], 3);
  EXPECT_EQ(b[4], 70000 & 0xFF);
  EXPECT_EQ(b[5], (70000 >> 8) & 0xFF);
  EXPECT_EQ(b[24], 2);
  EXPECT_EQ(b[25], 7);
  const ClvHeader r = decode_clv_header(b.data(), "h");
  EXPECT_EQ(r.dims, h.dims);
  EXPECT_EQ(r.cell_shape, h.cell_shape);
  EXPECT_EQ(r.order, ClvOrder::kBlocked);
  EXPECT_EQ(r.block_side, 7);
}

// ---- layouts ----------------------------------------------------------------------------------

TEST(BrickedVolume, EveryVoxelIsWhereTheLayoutSaysAndTheCopyRoundTrips) {
  const Volume v = small_shapes(23, 17, 30);
  for (int side : {2, 3, 4, 8, 16, 64}) {
    const BrickedVolume b = BrickedVolume::from_volume(v, side);
    const auto s = b.samples<std::uint8_t>();
    for (int a = 0; a < 3; ++a) EXPECT_EQ(s.nb[a], BrickedVolume::blocks_per_axis(v.dims()[std::size_t(a)], side));
    for (int k = 0; k < v.nz(); ++k)
      for (int j = 0; j < v.ny(); ++j)
        for (int i = 0; i < v.nx(); ++i) {
          ASSERT_EQ(b.value(i, j, k), v.value(i, j, k)) << side;
          // A voxel on a shared plane is stored in both blocks (the one-voxel overlap).
          if (side > 2 && i % (side - 1) == 0 && i > 0 && i / (side - 1) < s.nb[0]) {
            const int bx = i / (side - 1) - 1, by = s.block_of(j, 1), bz = s.block_of(k, 2);
            ASSERT_EQ(float(s.block(bx, by, bz)[s.local(side - 1, j - by * (side - 1), k - bz * (side - 1))]),
                      v.value(i, j, k));
          }
        }
    const Volume back = b.to_volume();
    for (int k = 0; k < v.nz(); ++k)
      for (int j = 0; j < v.ny(); ++j)
        for (int i = 0; i < v.nx(); ++i) ASSERT_EQ(back.value(i, j, k), v.value(i, j, k));
  }
}

TEST(BrickedVolume, EdgeBlocksArePaddedWithZeros) {
  const Volume v = small_shapes(20, 20, 20, 40, 8, 3);
  const BrickedVolume b = BrickedVolume::from_volume(v, 8);  // n_b = ceil(19/7) = 3: voxels up to 21
  const auto s = b.samples<std::uint8_t>();
  const std::uint8_t* last = s.block(2, 2, 2);
  int beyond = 0;
  for (int lx = 0; lx < 8; ++lx)
    for (int ly = 0; ly < 8; ++ly)
      for (int lz = 0; lz < 8; ++lz)
        if (14 + lx >= 20 || 14 + ly >= 20 || 14 + lz >= 20) {
          ++beyond;
          ASSERT_EQ(last[s.local(lx, ly, lz)], 0);
        }
  EXPECT_GT(beyond, 0);
}

// ---- files ------------------------------------------------------------------------------------

TEST(ClvFile, BothOrdersRoundTripInRamAndMappedAsBytesOrFloats) {
  const TempFolder dir;
  const Volume v = small_shapes(21, 18, 25);
  const auto lin = dir / "v.clv", blk = dir / "b.clv";
  write_clv(lin, v, ClvOrder::kLinear);
  write_clv(blk, v, ClvOrder::kBlocked, 6);
  EXPECT_EQ(std::int64_t(std::filesystem::file_size(lin)), 26 + 21 * 18 * 25);
  EXPECT_EQ(std::int64_t(std::filesystem::file_size(blk)), 26 + BrickedVolume::stored_samples({21, 18, 25}, 6));
  // The linear file is z fastest: byte 26 + z + y nz + x ny nz.
  const std::string bytes = bytes_of(lin);
  EXPECT_EQ(std::uint8_t(bytes[std::size_t(26 + 4 + 3 * 25 + 2 * 18 * 25)]), std::uint8_t(v.value(2, 3, 4)));
  for (auto memory : {ClvMemory::kRam, ClvMemory::kMmap})
    for (auto samples : {ClvSamples::kStored, ClvSamples::kFloat32}) {
      const ClvVolume a = open_clv(lin, memory, samples), b = open_clv(blk, memory, samples);
      ASSERT_FALSE(a.blocked());
      ASSERT_TRUE(b.blocked());
      EXPECT_EQ(a.linear.type(), samples == ClvSamples::kFloat32 ? SampleType::kFloat32 : SampleType::kUint8);
      EXPECT_EQ(b.bricked.side(), 6);
      EXPECT_EQ(a.linear.placement(), SamplePlacement::kNodes);
      EXPECT_EQ(a.linear.domain().hi, Eigen::Vector3d(20, 17, 24));
      for (int k = 0; k < v.nz(); ++k)
        for (int j = 0; j < v.ny(); ++j)
          for (int i = 0; i < v.nx(); ++i) {
            ASSERT_EQ(a.linear.value(i, j, k), v.value(i, j, k));
            ASSERT_EQ(b.bricked.value(i, j, k), v.value(i, j, k));
          }
    }
  // A bricked volume writes the same file as the volume it came from.
  write_clv(dir / "b2.clv", BrickedVolume::from_volume(v, 6));
  EXPECT_EQ(bytes_of(dir / "b2.clv"), bytes_of(blk));
}

TEST(ClvFile, TheMappedVolumeOutlivesItsOpener) {
  const TempFolder dir;
  const Volume v = small_shapes(9, 9, 9, 3, 4);
  write_clv(dir / "v.clv", v, ClvOrder::kLinear);
  Volume kept;
  {
    const ClvVolume c = open_clv(dir / "v.clv", ClvMemory::kMmap);
    kept = c.linear;
  }
  EXPECT_EQ(kept.value(4, 5, 6), v.value(4, 5, 6));
}

TEST(ClvFile, BadFilesAreRefusedWithOneLineNamingTheFile) {
  const TempFolder dir;
  auto refused = [&](const std::string& name, const std::string& content) {
    const auto f = dir / name;
    write_bytes(f, content);
    const std::string m = message_of([&] { (void)open_clv(f, ClvMemory::kMmap); });
    EXPECT_THAT(m, HasSubstr(f.string())) << name;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m;
  };
  const std::string body(4 * 4 * 4, '\x05');
  EXPECT_THAT(refused("short.clv", header_bytes(4, 4, 4, 1, 0).substr(0, 20)), HasSubstr("shorter than the 26-byte"));
  EXPECT_THAT(refused("lying.clv", header_bytes(4, 4, 5, 1, 0) + body), HasSubstr("declares 4 x 4 x 5"));
  EXPECT_THAT(refused("truncated.clv", header_bytes(4, 4, 4, 1, 0) + body.substr(1)), HasSubstr("holds 89 bytes"));
  EXPECT_THAT(refused("order.clv", header_bytes(4, 4, 4, 3, 0) + body), HasSubstr("order"));
  EXPECT_THAT(refused("order0.clv", header_bytes(4, 4, 4, 0, 0) + body), HasSubstr("order"));
  EXPECT_THAT(refused("side_linear.clv", header_bytes(4, 4, 4, 1, 16) + body), HasSubstr("must be 0"));
  EXPECT_THAT(refused("side_one.clv", header_bytes(4, 4, 4, 2, 1) + body), HasSubstr("block side"));
  EXPECT_THAT(refused("zero.clv", header_bytes(0, 4, 4, 1, 0) + body), HasSubstr("invalid"));
  EXPECT_THAT(refused("huge.clv", header_bytes(0xFFFFFFFFu, 0xFFFFFFFFu, 0xFFFFFFFFu, 1, 0) + body),
              HasSubstr("invalid"));
  // Each dimension valid, their product far beyond int64 / the limits.
  EXPECT_THAT(refused("overflow.clv", header_bytes(2000000000u, 2000000000u, 2000000000u, 1, 0) + body),
              HasSubstr("overflow"));
  EXPECT_THAT(refused("limit.clv", header_bytes(100000, 100000, 100000, 1, 0) + body), HasSubstr("exceeds the limit"));
  EXPECT_THAT(refused("shape.clv", header_bytes(4, 4, 4, 1, 0, std::nanf("")) + body), HasSubstr("cell shape"));
  EXPECT_THAT(refused("blocks_short.clv", header_bytes(4, 4, 4, 2, 2) + body), HasSubstr("in blocks of 2³"));
  EXPECT_THAT(message_of([&] { (void)open_clv(dir / "missing.clv"); }), HasSubstr("missing.clv"));
}

// ---- the streamed writer -------------------------------------------------------------------------

TEST(ClvFile, TheOrderGeneratorVisitsEveryVoxelOnceInFileOrder) {
  for (auto order : {ClvOrder::kLinear, ClvOrder::kBlocked}) {
    VoxelOrder o({7, 9, 11}, order, 4);
    std::vector<VoxelCoord> all;
    std::vector<VoxelCoord> batch(5);
    while (std::size_t n = o.next(batch.data(), batch.size()))
      all.insert(all.end(), batch.begin(), batch.begin() + long(n));
    ASSERT_EQ(std::int64_t(all.size()), o.total());
    std::set<std::tuple<int, int, int>> inside;
    for (const auto& c : all)
      if (c.x < 7 && c.y < 9 && c.z < 11) inside.insert({c.x, c.y, c.z});
    EXPECT_EQ(inside.size(), 7u * 9u * 11u);
    if (order == ClvOrder::kLinear) {
      EXPECT_EQ(all[1].z, 1);  // z fastest
      EXPECT_EQ(all[11].y, 1);
    } else {
      EXPECT_EQ(o.total(), BrickedVolume::stored_samples({7, 9, 11}, 4));
      EXPECT_EQ(all[4].z, 0);  // the block's second row
      EXPECT_EQ(all[4].y, 1);
      EXPECT_EQ(all[64].z, 3);  // the next block (along z) starts on the shared plane
    }
  }
}

TEST(ClvFile, BatchedParallelGenerationWritesTheNaiveWritersBytes) {
  const TempFolder dir;
  ShapesOptions so;
  so.dims = {30, 26, 41};
  so.count = 15;
  so.object_size = 10;
  const ShapesVolume shapes(so);
  for (auto order : {ClvOrder::kLinear, ClvOrder::kBlocked}) {
    ClvWriteOptions fast;
    fast.order = order;
    fast.block_side = 8;
    fast.batch = 1000;  // several batches, the last one short
    ClvWriteOptions naive = fast;
    naive.batch = 1;
    naive.parallel = false;
    const auto a = write_clv_generated(dir / "a.clv", so.dims, shapes, fast);
    const auto b = write_clv_generated(dir / "b.clv", so.dims, shapes, naive);
    EXPECT_EQ(a.bytes, b.bytes);
    EXPECT_EQ(bytes_of(dir / "a.clv"), bytes_of(dir / "b.clv"));
    const ClvVolume r = open_clv(dir / "a.clv");
    for (int k = 0; k < 41; k += 3)
      for (int j = 0; j < 26; j += 2)
        for (int i = 0; i < 30; ++i)
          ASSERT_EQ(order == ClvOrder::kLinear ? r.linear.value(i, j, k) : r.bricked.value(i, j, k),
                    float(shapes.value(i, j, k)));
  }
}

// ---- the shapes generator -------------------------------------------------------------------------

TEST(Shapes, TheShapesFollowTheRulesOfSection29) {
  ShapesOptions so;
  so.dims = {120, 100, 90};
  so.count = 400;
  so.object_size = 30;
  so.sample = 100;
  const ShapesVolume v(so);
  ASSERT_EQ(v.shapes().size(), 400u);
  int spheres = 0;
  std::set<int> values, sizes;
  for (const Shape& s : v.shapes()) {
    spheres += s.sphere;
    values.insert(s.value);
    for (int a = 0; a < 3; ++a) {
      sizes.insert(s.size[std::size_t(a)]);
      EXPECT_GE(s.size[std::size_t(a)], 30 - 10);
      EXPECT_LE(s.size[std::size_t(a)], 30 + 10);
      EXPECT_GE(s.lo[std::size_t(a)], 0);
      EXPECT_LE(s.lo[std::size_t(a)] + s.size[std::size_t(a)], so.dims[std::size_t(a)]);
    }
  }
  // Binomial(400, 1/2): mean 200, sd 10; 5 sd either way.
  EXPECT_NEAR(spheres, 200, 50);
  EXPECT_EQ(*values.begin(), 90);  // all 21 values drawn (each missing with p ≈ e^-19)
  EXPECT_EQ(*values.rbegin(), 110);
  EXPECT_EQ(values.size(), 21u);
  EXPECT_EQ(sizes.size(), 21u);
  // The first shape in list order decides; a sphere is 0 outside its ball.
  for (int t = 0; t < 20000; ++t) {
    const int x = int((std::int64_t(t) * 7919) % 120), y = int((std::int64_t(t) * 104729) % 100),
              z = int((std::int64_t(t) * 1299709) % 90);
    std::uint8_t expected = 0;
    for (const Shape& s : v.shapes()) {
      bool in = true;
      for (int a = 0; a < 3; ++a) {
        const int p = a == 0 ? x : a == 1 ? y : z;
        in = in && p >= s.lo[std::size_t(a)] && p < s.lo[std::size_t(a)] + s.size[std::size_t(a)];
      }
      if (!in) continue;
      if (s.sphere) {
        const double r = s.size[0] / 2.0;
        const double dx = x - (s.lo[0] + s.size[0] / 2.0), dy = y - (s.lo[1] + s.size[1] / 2.0),
                     dz = z - (s.lo[2] + s.size[2] / 2.0);
        expected = dx * dx + dy * dy + dz * dz <= r * r ? s.value : 0;
      } else {
        expected = s.value;
      }
      break;
    }
    ASSERT_EQ(v.value(x, y, z), expected) << x << " " << y << " " << z;
  }
  // The same seed gives the same shapes; another seed others.
  EXPECT_EQ(ShapesVolume(so).shapes()[7].lo, v.shapes()[7].lo);
  so.seed = 3;
  EXPECT_NE(ShapesVolume(so).shapes()[7].lo, v.shapes()[7].lo);
}

TEST(Shapes, BadOptionsAreRefused) {
  ShapesOptions so;
  so.dims = {50, 50, 50};
  so.object_size = 40;  // 40 + 13 > 50
  EXPECT_THAT(message_of([&] { ShapesVolume v(so); }), HasSubstr("do not fit"));
  so.object_size = 0;
  EXPECT_THAT(message_of([&] { ShapesVolume v(so); }), HasSubstr("object size"));
  so.object_size = 10;
  so.sample = 250;
  EXPECT_THAT(message_of([&] { ShapesVolume v(so); }), HasSubstr("sample value"));
}

TEST(Shapes, TheSkullPhantomIsOpaqueBoneInsideTransparentTissue) {
  const SkullPhantom skull({64, 64, 17});
  const TransferFunction tf = TransferFunction::skull();
  int bone = 0, total = 0;
  for (int k = 0; k < 17; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i, ++total) bone += tf.visible_at(skull.value(i, j, k));
  // A shell: present, and a small part of the slab.
  EXPECT_GT(bone, total / 50);
  EXPECT_LT(bone, total / 3);
  EXPECT_FALSE(tf.visible_at(skull.value(0, 0, 0)));    // air
  EXPECT_FALSE(tf.visible_at(skull.value(32, 32, 8)));  // brain (or a ventricle)
}

// ---- transfer functions -------------------------------------------------------------------------

TEST(TransferFunction, TheSpecsTablesAndTheirCharacteristic) {
  const TransferFunction tf = TransferFunction::shapes();
  EXPECT_EQ(tf.find(85.0), -1);
  EXPECT_EQ(tf.find(85.0001), 0);
  EXPECT_EQ(tf.find(95.0), 0);
  EXPECT_EQ(tf.find(100.0), 1);
  EXPECT_EQ(tf.find(114.999), 2);
  EXPECT_EQ(tf.find(115.0), -1);
  EXPECT_FALSE(tf.visible_in(0, 85));  // (85, 95] starts after 85
  EXPECT_TRUE(tf.visible_in(0, 85.01));
  EXPECT_FALSE(tf.visible_in(115, 255));  // (100, 115) ends before 115
  EXPECT_TRUE(tf.visible_in(114.5, 255));
  // An interval can hold a visible value although neither end is: the voxel test misses it.
  EXPECT_TRUE(tf.visible_in(0, 120));
  EXPECT_FALSE(tf.visible_at(0));
  EXPECT_FALSE(tf.visible_at(120));
  TfRange r;
  parse_tf_bounds(" [ 1.5 ,2) ", r, "t");
  EXPECT_EQ(r.lo, 1.5);
  EXPECT_EQ(r.hi, 2);
  EXPECT_TRUE(r.lo_closed);
  EXPECT_FALSE(r.hi_closed);
  for (const char* bad : {"(1, 2", "1, 2]", "(a, 2]", "(1; 2]", "(1, 2, 3]", "()"})
    EXPECT_THAT(message_of([&] { parse_tf_bounds(bad, r, "tf"); }), HasSubstr("not a value range")) << bad;
  std::vector<TfRange> overlapping(2);
  parse_tf_bounds("(0, 10]", overlapping[0], "t");
  parse_tf_bounds("[10, 20]", overlapping[1], "t");
  EXPECT_THAT(message_of([&] { TransferFunction t(overlapping); }), HasSubstr("overlap"));
  overlapping[1].lo_closed = false;  // (0, 10] and (10, 20] touch without overlapping
  EXPECT_NO_THROW(TransferFunction t(overlapping));
}

TEST(TransferFunction, OpacityCorrectionAndItsErratum) {
  // α = 1 - (1 - α0)^{s/s0}: n steps of s compose to one step of n s.
  const double a0 = 0.3;
  const double a = corrected_opacity(a0, 0.2, 1.0, OpacityExponent::kStepOverReference);
  EXPECT_NEAR(1 - std::pow(1 - a, 5), a0, 1e-12);
  // The printed exponent s0/s makes a small step more opaque than a large one.
  EXPECT_GT(corrected_opacity(a0, 0.2, 1.0, OpacityExponent::kReferenceOverStep), a0);
  EXPECT_EQ(corrected_opacity(1.0, 0.2, 1.0, OpacityExponent::kStepOverReference), 1.0);
  EXPECT_EQ(corrected_opacity(0.0, 0.2, 1.0, OpacityExponent::kStepOverReference), 0.0);
}

// ---- the memory map -----------------------------------------------------------------------------

TEST(MappedFile, MapsTheBytesAndRefusesWhatCannotBeMapped) {
  const TempFolder dir;
  write_bytes(dir / "f.bin", std::string("abcdef"));
  const auto m = MappedFile::open(dir / "f.bin", "test file");
  ASSERT_EQ(m->size(), 6);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(m->data()), 6), "abcdef");
  m->advise(MappedFile::Advice::kRandom);
  EXPECT_TRUE(evict_from_page_cache(dir / "f.bin"));
  EXPECT_EQ(m->data()[3], 'd');
  write_bytes(dir / "empty.bin", "");
  EXPECT_THAT(message_of([&] { (void)MappedFile::open(dir / "empty.bin", "test file"); }), HasSubstr("empty.bin"));
  EXPECT_THAT(message_of([&] { (void)MappedFile::open(dir.path(), "test file"); }), HasSubstr(dir.path().string()));
}

}  // namespace
}  // namespace meltlab::render
