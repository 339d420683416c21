// Seed 003's VLB files and normalisation (render/volume/vlb_file.h, scalar_volume.h): round trips
// of every sample type in both byte orders, one test per header refusal (each naming FILE:LINE),
// the normalisation extremes of spec §5.9, and the texture-memory arithmetic of §2.3 with its
// erratum.

#include <meltlab/core/error.h>
#include <meltlab/core/limits.h>
#include <meltlab/render/volume/scalar_volume.h>
#include <meltlab/render/volume/texture_memory.h>
#include <meltlab/render/volume/vlb_file.h>
#include <meltlab/render/volume/volume_io.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "test_files.h"

namespace meltlab::render {
namespace {

using test::message_of;
using test::TempFolder;
using ::testing::HasSubstr;

constexpr ScalarType kAllTypes[] = {ScalarType::kInt8,    ScalarType::kUint8,  ScalarType::kInt16,
                                    ScalarType::kUint16,  ScalarType::kInt32,  ScalarType::kUint32,
                                    ScalarType::kFloat32, ScalarType::kFloat64};

/// A 5 x 4 x 3 volume whose samples reach both ends of the type's range (so a byte-order or
/// sign error changes values) and differ per position (so an order error does too).
ScalarVolume ramp(ScalarType type) {
  ScalarVolume v = ScalarVolume::allocate({5, 4, 3}, type);
  v.spacing = Eigen::Vector3d(0.5, 1.25, 2.0);
  const bool is_signed = type == ScalarType::kInt8 || type == ScalarType::kInt16 || type == ScalarType::kInt32;
  const double lo = type == ScalarType::kFloat32   ? -3.0e38
                    : type == ScalarType::kFloat64 ? -1.5e300
                    : is_signed                    ? -std::ldexp(1.0, scalar_bytes(type) * 8 - 1)
                                                   : 0.0;
  const double hi = type == ScalarType::kFloat32   ? 3.25e38
                    : type == ScalarType::kFloat64 ? 1.25e300
                                                   : std::ldexp(1.0, scalar_bytes(type) * 8 - (is_signed ? 1 : 0)) - 1;
  for (std::int64_t n = 0; n < v.sample_count(); ++n) v.set_value(n, lo + (hi - lo) * double(n) / 59.0);
  v.set_value(7, lo);
  v.set_value(31, hi);
  if (type == ScalarType::kFloat32 || type == ScalarType::kFloat64) v.set_value(11, -0.0), v.set_value(12, 1e-30);
  return v;
}

std::string write_text(const TempFolder& dir, const std::string& name, const std::string& header,
                       std::size_t sample_bytes) {
  const auto path = dir.path() / name;
  std::ofstream out(path, std::ios::binary);
  out << header << std::string(sample_bytes, '\x01');
  return path.string();
}

const std::string kGood = "VLB.1\n2 2 2\nint16\nlittle\n1. 1. 2.\n-1117 2248\n0 1\n";

TEST(Vlb, RoundTripEveryTypeBothEndians) {
  const TempFolder dir;
  for (ScalarType type : kAllTypes)
    for (std::endian e : {std::endian::little, std::endian::big}) {
      const ScalarVolume v = ramp(type);
      const auto file =
          dir.path() / fmt::format("{}_{}.vlb", scalar_type_name(type), e == std::endian::big ? "be" : "le");
      VlbWriteOptions o;
      o.endian = e;
      write_vlb(file, v, o);
      const VlbFile r = read_vlb(file);
      SCOPED_TRACE(file.string());
      EXPECT_EQ(r.header.dims, v.dims);
      EXPECT_EQ(r.header.type, type);
      EXPECT_EQ(r.header.endian, e);
      EXPECT_EQ(r.header.spacing, v.spacing);
      // Bit-exact samples (the reader swaps back to native order).
      EXPECT_EQ(r.volume.bytes, v.bytes);
      const auto range = v.scanned_range();
      EXPECT_EQ(r.header.min, range[0]);  // printed with 17 digits: exact
      EXPECT_EQ(r.header.max, range[1]);
      // The file is 7 header lines + exactly the samples.
      EXPECT_EQ(std::int64_t(std::filesystem::file_size(file)),
                r.header.header_bytes + v.sample_count() * scalar_bytes(type));
    }
}

TEST(Vlb, BigEndianBytesAreBigEndianOnDisk) {
  const TempFolder dir;
  ScalarVolume v = ScalarVolume::allocate({1, 1, 1}, ScalarType::kInt16);
  v.set_value(0, 258);  // 0x0102
  VlbWriteOptions o;
  o.endian = std::endian::big;
  write_vlb(dir.path() / "b.vlb", v, o);
  const std::string bytes = test::read_file(dir.path() / "b.vlb");
  ASSERT_GE(bytes.size(), 2u);
  EXPECT_EQ(bytes[bytes.size() - 2], '\x01');
  EXPECT_EQ(bytes[bytes.size() - 1], '\x02');
}

TEST(Vlb, ReadsTheSourcesExampleHeaderAndCrLf) {
  const VlbHeader h =
      parse_vlb_header("VLB.1\r\n256 256 113\r\nint16\r\nlittle\r\n1. 1. 2.\r\n-1117 2248\r\n0 1\r\n", "head.vlb");
  EXPECT_EQ(h.dims, (std::array<int, 3>{256, 256, 113}));
  EXPECT_EQ(h.type, ScalarType::kInt16);
  EXPECT_EQ(h.spacing, Eigen::Vector3d(1, 1, 2));
  EXPECT_EQ(h.min, -1117);
  EXPECT_EQ(h.max, 2248);
  EXPECT_EQ(h.sample_bytes(), 256 * 256 * 113 * 2);
}

// ---- refusals: one per kind, each naming FILE:LINE --------------------------------------------

std::string refusal(const std::string& header, std::size_t sample_bytes = 16) {
  const TempFolder dir;
  const std::string f = write_text(dir, "v.vlb", header, sample_bytes);
  return message_of([&] { (void)read_vlb(f); });
}

std::string with_line(int n, const std::string& text) {
  std::vector<std::string> lines = {"VLB.1", "2 2 2", "int16", "little", "1. 1. 2.", "-1117 2248", "0 1"};
  lines[std::size_t(n - 1)] = text;
  std::string h;
  for (const auto& l : lines) h += l + "\n";
  return h;
}

TEST(Vlb, RefusesSampleCountThatDoesNotMatchTheFileSize) {
  EXPECT_THAT(refusal(kGood, 15), HasSubstr("v.vlb:2: the file holds 15 bytes of samples"));
  EXPECT_THAT(refusal(kGood, 17), HasSubstr("v.vlb:2: the file holds 17 bytes"));
}
TEST(Vlb, RefusesAnUnknownType) {
  EXPECT_THAT(refusal(with_line(3, "int24")), HasSubstr("v.vlb:3: unknown sample type 'int24'"));
  EXPECT_THAT(refusal(with_line(3, "int64")), HasSubstr("v.vlb:3: unknown sample type"));
}
TEST(Vlb, RefusesZeroDimensions) {
  EXPECT_THAT(refusal(with_line(2, "0 2 2"), 0), HasSubstr("v.vlb:2: dimension '0' is not a whole number"));
}
TEST(Vlb, RefusesNegativeAndFractionalDimensions) {
  EXPECT_THAT(refusal(with_line(2, "-2 2 2")), HasSubstr("v.vlb:2: dimension '-2'"));
  EXPECT_THAT(refusal(with_line(2, "2.5 2 2")), HasSubstr("v.vlb:2: dimension '2.5'"));
  EXPECT_THAT(refusal(with_line(2, "2 2")), HasSubstr("v.vlb:2: expected the dimensions"));
}
TEST(Vlb, RefusesAnOverflowingDimsProduct) {
  // 2^31-1 cubed overflows int64; 2^31-1 x 2^31-1 x 2 does not, but exceeds the sample limit.
  EXPECT_THAT(refusal(with_line(2, "2147483647 2147483647 2147483647")), HasSubstr("v.vlb:2: the sample count"));
  EXPECT_THAT(refusal(with_line(2, "2147483647 2147483647 2")), HasSubstr("v.vlb:2: volume samples"));
}
TEST(Vlb, RefusesATruncatedFile) {
  EXPECT_THAT(refusal("VLB.1\n2 2 2\nint16\n", 0), HasSubstr("v.vlb:4: the header ends before line 4"));
  EXPECT_THAT(refusal(kGood, 0), HasSubstr("v.vlb:2: the file holds 0 bytes of samples"));
}
TEST(Vlb, RefusesAWrongVersion) {
  EXPECT_THAT(refusal(with_line(1, "VLB.2")), HasSubstr("v.vlb:1: unsupported version 'VLB.2'"));
  EXPECT_THAT(refusal(with_line(1, "NRRD0004")), HasSubstr("v.vlb:1: not a VLB file"));
}
TEST(Vlb, RefusesABadEndianness) {
  EXPECT_THAT(refusal(with_line(4, "middle")), HasSubstr("v.vlb:4: unknown endianness 'middle'"));
}
TEST(Vlb, RefusesABadSpacing) {
  EXPECT_THAT(refusal(with_line(5, "1 0 1")), HasSubstr("v.vlb:5: spacing '0'"));
  EXPECT_THAT(refusal(with_line(5, "1 nan 1")), HasSubstr("v.vlb:5: spacing 'nan'"));
}
TEST(Vlb, RefusesAReversedRange) {
  EXPECT_THAT(refusal(with_line(6, "5 -5")), HasSubstr("v.vlb:6: the minimum 5 is greater than the maximum -5"));
}
TEST(Vlb, RefusesAnEmptyWindow) {
  EXPECT_THAT(refusal(with_line(7, "1 1")), HasSubstr("v.vlb:7: the window's lower bound"));
  EXPECT_THAT(refusal(with_line(7, "0")), HasSubstr("v.vlb:7: expected the recommended window"));
}
TEST(Vlb, RefusesALongLineWithoutReadingFurther) {
  EXPECT_THAT(refusal(std::string(5000, 'V'), 0), HasSubstr("v.vlb:1: line longer than 256 bytes"));
}
TEST(Vlb, RefusesNonFiniteFloatSamples) {
  const TempFolder dir;
  ScalarVolume v = ScalarVolume::allocate({2, 1, 1}, ScalarType::kFloat32);
  v.set_value(1, std::numeric_limits<double>::quiet_NaN());
  VlbWriteOptions o;
  o.range = std::array<double, 2>{0, 1};
  write_vlb(dir.path() / "n.vlb", v, o);
  EXPECT_THAT(message_of([&] { (void)read_vlb(dir.path() / "n.vlb"); }), HasSubstr("sample 1 is not a finite number"));
}

// ---- normalisation (§5.9) ---------------------------------------------------------------------

TEST(VlbNormalisation, ScannedExtremaMapToExactlyZeroAndOne) {
  for (ScalarType type : kAllTypes) {
    const ScalarVolume v = ramp(type);
    Normalisation n;
    const Volume f = normalised_volume(v, NormSource::kScanned, 0, 0, &n);
    const auto r = f.value_range();
    EXPECT_EQ(r[0], 0.0f) << scalar_type_name(type);
    EXPECT_EQ(r[1], 1.0f) << scalar_type_name(type);
    EXPECT_EQ(f.value(2, 1, 0), 0.0f);  // sample 7 holds the minimum
    EXPECT_EQ(f.value(1, 2, 1), 1.0f);  // sample 31 holds the maximum
    EXPECT_EQ(n.clipped_low + n.clipped_high, 0);
    EXPECT_EQ(f.spacing(), v.spacing);
    EXPECT_EQ(f.placement(), SamplePlacement::kNodes);
  }
}

TEST(VlbNormalisation, NegativeIntegersKeepTheirOrderAndSpacing) {
  ScalarVolume v = ScalarVolume::allocate({3, 1, 1}, ScalarType::kInt16);
  v.set_value(0, -1117);
  v.set_value(1, 0);
  v.set_value(2, 2248);
  const Volume f = normalised_volume(v, NormSource::kScanned, 0, 0);
  EXPECT_EQ(f.value(0, 0, 0), 0.0f);
  // (0 + 1117) / 3365, rounded once to float.
  EXPECT_EQ(f.value(1, 0, 0), static_cast<float>(1117.0 / 3365.0));
  EXPECT_EQ(f.value(2, 0, 0), 1.0f);
}

TEST(VlbNormalisation, ConstantVolumeIsZeroEverywhere) {
  ScalarVolume v = ScalarVolume::allocate({2, 2, 2}, ScalarType::kInt16);
  for (std::int64_t n = 0; n < 8; ++n) v.set_value(n, -500);
  Normalisation info;
  const Volume f = normalised_volume(v, NormSource::kScanned, 0, 0, &info);
  EXPECT_TRUE(info.constant);
  EXPECT_EQ(f.value_range(), (std::array<float, 2>{0.0f, 0.0f}));
}

TEST(VlbNormalisation, HeaderMinEqualsMaxIsConstant) {
  const VlbHeader h = parse_vlb_header(with_line(6, "7 7"), "c.vlb");
  const auto range = vlb_norm_range(h, NormSource::kHeader, VlbWindowUnits::kFraction);
  ScalarVolume v = ScalarVolume::allocate({2, 1, 1}, ScalarType::kInt16);
  v.set_value(0, 3);
  v.set_value(1, 9);
  Normalisation info;
  const Volume f = normalised_volume(v, NormSource::kHeader, range[0], range[1], &info);
  EXPECT_TRUE(info.constant);
  EXPECT_EQ(f.value(0, 0, 0), 0.0f);
  EXPECT_EQ(f.value(1, 0, 0), 0.0f);
}

TEST(VlbNormalisation, WindowClipsAndCounts) {
  // Header range [-1000, 1000]; window 0.25..0.75 as fractions = [-500, 500].
  const VlbHeader h = parse_vlb_header("VLB.1\n4 1 1\nint16\nlittle\n1 1 1\n-1000 1000\n0.25 0.75\n", "w.vlb");
  const auto frac = vlb_norm_range(h, NormSource::kWindow, VlbWindowUnits::kFraction);
  EXPECT_EQ(frac, (std::array<double, 2>{-500, 500}));
  const auto value = vlb_norm_range(h, NormSource::kWindow, VlbWindowUnits::kValue);
  EXPECT_EQ(value, (std::array<double, 2>{0.25, 0.75}));
  ScalarVolume v = ScalarVolume::allocate({4, 1, 1}, ScalarType::kInt16);
  v.set_value(0, -1000);
  v.set_value(1, -500);
  v.set_value(2, 250);
  v.set_value(3, 1000);
  Normalisation info;
  const Volume f = normalised_volume(v, NormSource::kWindow, frac[0], frac[1], &info);
  EXPECT_EQ(f.value(0, 0, 0), 0.0f);   // clipped
  EXPECT_EQ(f.value(1, 0, 0), 0.0f);   // the window's lower end
  EXPECT_EQ(f.value(2, 0, 0), 0.75f);  // (250 + 500) / 1000, exact in binary
  EXPECT_EQ(f.value(3, 0, 0), 1.0f);   // clipped
  EXPECT_EQ(info.clipped_low, 1);
  EXPECT_EQ(info.clipped_high, 1);
}

TEST(VlbNormalisation, NoneKeepsTheStoredValues) {
  ScalarVolume v = ScalarVolume::allocate({2, 1, 1}, ScalarType::kInt16);
  v.set_value(0, -1117);
  v.set_value(1, 2248);
  const Volume f = normalised_volume(v, NormSource::kNone, 0, 0);
  EXPECT_EQ(f.value(0, 0, 0), -1117.0f);
  EXPECT_EQ(f.value(1, 0, 0), 2248.0f);
}

TEST(VlbNormalisation, ReadVolumeAppliesTheOptions) {
  const TempFolder dir;
  ScalarVolume v = ScalarVolume::allocate({3, 1, 1}, ScalarType::kInt16);
  v.set_value(0, -100);
  v.set_value(1, 0);
  v.set_value(2, 100);
  // Header range wider than the data: [-200, 200].
  VlbWriteOptions o;
  o.endian = std::endian::big;
  o.range = std::array<double, 2>{-200, 200};
  write_vlb(dir.path() / "h.vlb", v, o);
  VolumeReadInfo info;
  const Volume scanned = read_volume(dir.path() / "h.vlb", {}, &info);
  EXPECT_EQ(scanned.value(0, 0, 0), 0.0f);
  EXPECT_EQ(scanned.value(2, 0, 0), 1.0f);
  EXPECT_EQ(info.format, "vlb");
  VolumeReadOptions ro;
  ro.norm = NormSource::kHeader;
  const Volume header = read_volume(dir.path() / "h.vlb", ro);
  EXPECT_EQ(header.value(0, 0, 0), 0.25f);
  EXPECT_EQ(header.value(1, 0, 0), 0.5f);
  EXPECT_EQ(header.value(2, 0, 0), 0.75f);
  EXPECT_EQ(header.spacing(), Eigen::Vector3d::Ones());
}

// ---- §2.3: the memory arithmetic of the source's example --------------------------------------

TEST(VlbTextureMemory, SourceExampleAndItsMaskErratum) {
  const SlicingTextureBytes b = slicing_texture_bytes({250, 250, 150}, {100, 100, 100});
  EXPECT_EQ(b.data, 18'750'000);       // 9 375 000 voxels x 2 B (ALPHA16)
  EXPECT_EQ(b.normals, 28'125'000);    // x 3 B (RGB8)
  EXPECT_EQ(b.mask, 500'000);          // 10^6 voxels x 4 bits: the source prints 5 000 000 (erratum)
  EXPECT_EQ(b.volumes(), 47'375'000);  // the source's printed total: consistent with 500 000 B only
  EXPECT_NE(b.data + b.normals + 5'000'000, 47'375'000);
  // "45.2 MB" is MiB: 47 375 000 / 2^20 = 45.18.
  EXPECT_NEAR(double(b.volumes()) / (1 << 20), 45.2, 0.05);
  // Odd voxel counts round up to whole bytes; render targets RGBA16F at 8 B per pixel.
  EXPECT_EQ(slicing_texture_bytes({1, 1, 1}, {3, 1, 1}).mask, 2);
  EXPECT_EQ(render_target_bytes(1000, 730, 2), 11'680'000);
}

}  // namespace
}  // namespace meltlab::render
