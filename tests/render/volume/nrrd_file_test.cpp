// NRRD volumes (render/volume/nrrd_file.h): round trips through the files the test writes
// (attached and detached, raw and gzip, both byte orders), headers as 3D Slicer and teem write
// them, and refusals naming FILE:LINE or the data file.

#include <meltlab/core/error.h>
#include <meltlab/render/volume/nrrd_file.h>
#include <meltlab/render/volume/volume_io.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "test_files.h"

namespace meltlab::render {
namespace {

using test::message_of;
using test::TempFolder;
using ::testing::HasSubstr;

ScalarVolume sample_volume(ScalarType type) {
  ScalarVolume v = ScalarVolume::allocate({6, 5, 4}, type);
  v.spacing = Eigen::Vector3d(0.75, 0.75, 2.5);
  v.origin = Eigen::Vector3d(-10, 4.5, 100);
  for (std::int64_t n = 0; n < v.sample_count(); ++n) v.set_value(n, double((n * 37) % 120) - 60.0);
  return v;
}

void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

TEST(Nrrd, RoundTripAttachedDetachedRawGzipBothEndians) {
  const TempFolder dir;
  for (ScalarType type : {ScalarType::kInt8, ScalarType::kUint8, ScalarType::kInt16, ScalarType::kUint16,
                          ScalarType::kInt32, ScalarType::kUint32, ScalarType::kFloat32, ScalarType::kFloat64})
    for (const char* ext : {".nrrd", ".nhdr"})
      for (NrrdEncoding enc : {NrrdEncoding::kRaw, NrrdEncoding::kGzip})
        for (std::endian e : {std::endian::little, std::endian::big}) {
          const ScalarVolume v = sample_volume(type);
          const auto file = dir.path() / fmt::format("v_{}_{}_{}{}", scalar_type_name(type),
                                                     enc == NrrdEncoding::kGzip ? "gz" : "raw",
                                                     e == std::endian::big ? "be" : "le", ext);
          NrrdWriteOptions o;
          o.encoding = enc;
          o.endian = e;
          write_nrrd(file, v, o);
          NrrdHeader h;
          const ScalarVolume r = read_nrrd(file, &h);
          SCOPED_TRACE(file.string());
          EXPECT_EQ(r.dims, v.dims);
          EXPECT_EQ(r.type, type);
          EXPECT_EQ(r.bytes, v.bytes);
          EXPECT_EQ(r.spacing, v.spacing);
          EXPECT_EQ(r.origin, v.origin);
          EXPECT_EQ(h.encoding, enc);
          EXPECT_EQ(h.data_file.empty(), std::string(ext) == ".nrrd");
        }
}

TEST(Nrrd, ReadsASlicerStyleHeaderWithMirroredAxesAndCellCentres) {
  const TempFolder dir;
  std::string h =
      "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\n"
      "type: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 2 1 1\n"
      "space directions: (-0.5,0,0) (0,-0.5,0) (0,0,2)\nkinds: domain domain domain\ncenters: cell cell cell\n"
      "endian: little\nencoding: raw\nspace origin: (1,2,3)\nDICOM_tag:=value\n\n";
  write_bytes(dir.path() / "s.nrrd", h + std::string("\x01\x00\xff\xff", 4));
  NrrdHeader header;
  const ScalarVolume v = read_nrrd(dir.path() / "s.nrrd", &header);
  EXPECT_EQ(v.type, ScalarType::kInt16);
  EXPECT_EQ(v.value(0), 1);
  EXPECT_EQ(v.value(1), -1);
  EXPECT_EQ(v.spacing, Eigen::Vector3d(0.5, 0.5, 2));
  EXPECT_EQ(v.origin, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(header.placement, SamplePlacement::kCellCentred);
  EXPECT_TRUE(header.mirrored[0] && header.mirrored[1] && !header.mirrored[2]);
  // read_volume: normalised by the scanned extrema, the header's placement.
  const Volume f = read_volume(dir.path() / "s.nrrd");
  EXPECT_EQ(f.value(0, 0, 0), 1.0f);
  EXPECT_EQ(f.value(1, 0, 0), 0.0f);
  EXPECT_EQ(f.placement(), SamplePlacement::kCellCentred);
}

TEST(Nrrd, ByteSkipMinusOneAndLineSkip) {
  const TempFolder dir;
  write_bytes(dir.path() / "d.raw", std::string("junk line\n") + "XYZ" + std::string("\x05\x06", 2));
  write_bytes(dir.path() / "a.nhdr",
              "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 1 1\nencoding: raw\nbyte skip: -1\ndata file: d.raw\n");
  EXPECT_EQ(read_nrrd(dir.path() / "a.nhdr").value(1), 6);
  write_bytes(dir.path() / "b.nhdr",
              "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 1 1\nencoding: raw\nline skip: "
              "1\nbyte skip: 3\ndata file: d.raw\n");
  const ScalarVolume b = read_nrrd(dir.path() / "b.nhdr");
  EXPECT_EQ(b.value(0), 5);
  EXPECT_EQ(b.value(1), 6);
}

std::string refusal(const std::string& header, const std::string& data = std::string(16, '\0')) {
  const TempFolder dir;
  write_bytes(dir.path() / "v.nrrd", header + data);
  return message_of([&] { (void)read_nrrd(dir.path() / "v.nrrd"); });
}

const std::string kHead = "NRRD0004\ntype: int16\ndimension: 3\nsizes: 2 2 2\nendian: little\n";

TEST(Nrrd, RefusesBadHeadersNamingTheLine) {
  EXPECT_THAT(refusal("P6\n"), HasSubstr("v.nrrd:1: not a NRRD file"));
  EXPECT_THAT(refusal(kHead + "encoding: ascii\n\n"), HasSubstr("v.nrrd:6: encoding 'ascii' is not supported"));
  EXPECT_THAT(refusal(kHead + "encoding: bzip2\n\n"), HasSubstr("v.nrrd:6: encoding 'bzip2' is not supported"));
  EXPECT_THAT(refusal("NRRD0004\ntype: int16\ndimension: 4\n"), HasSubstr("v.nrrd:3: dimension 4"));
  EXPECT_THAT(refusal("NRRD0004\ntype: longlong\n"), HasSubstr("v.nrrd:2: type 'longlong': 64-bit"));
  EXPECT_THAT(refusal("NRRD0004\ntype: quaternion\n"), HasSubstr("v.nrrd:2: unknown type"));
  EXPECT_THAT(refusal("NRRD0004\nsizes: 0 2 2\n"), HasSubstr("v.nrrd:2: size '0'"));
  EXPECT_THAT(refusal("NRRD0004\nsizes: 2147483647 2147483647 2147483647\n"), HasSubstr("v.nrrd:2: the sample count"));
  EXPECT_THAT(refusal(kHead + "encoding: raw\nspace directions: (1,1,0) (0,1,0) (0,0,1)\n\n"),
              HasSubstr("v.nrrd:7: space direction (1,1,0) is oblique"));
  EXPECT_THAT(refusal(kHead + "encoding: raw\nspacings: 1 0 1\n\n"), HasSubstr("v.nrrd:7: spacing '0'"));
  EXPECT_THAT(refusal(kHead + "encoding: raw\ncolour: red\n\n"), HasSubstr("v.nrrd:7: unknown field 'colour'"));
  EXPECT_THAT(refusal(kHead + "encoding: raw\nsizes: 2 2 2\n\n"), HasSubstr("v.nrrd:7: field 'sizes' given twice"));
  EXPECT_THAT(refusal("NRRD0004\ntype: int16\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n"),
              HasSubstr("no 'endian' field"));
  EXPECT_THAT(refusal(kHead + "encoding: raw\n", ""), HasSubstr("neither a 'data file' nor an empty line"));
}

TEST(Nrrd, RefusesDataThatDoNotMatchTheHeader) {
  EXPECT_THAT(refusal(kHead + "encoding: raw\n\n", std::string(15, '\0')), HasSubstr("holds 15 bytes of samples"));
  EXPECT_THAT(refusal(kHead + "encoding: raw\n\n", std::string(17, '\0')), HasSubstr("holds 17 bytes of samples"));
  EXPECT_THAT(refusal(kHead + "encoding: gzip\n\n", "not gzip at all"), HasSubstr("gzip data"));
  const TempFolder dir;
  write_bytes(dir.path() / "m.nhdr", kHead + "encoding: raw\ndata file: missing.raw\n");
  EXPECT_THAT(message_of([&] { (void)read_nrrd(dir.path() / "m.nhdr"); }), HasSubstr("missing.raw"));
}

TEST(Nrrd, RefusesGzipDataLongerOrShorterThanDeclared) {
  const TempFolder dir;
  // A gzip stream of 16 bytes, declared as 2 x 2 x 1 int16 (8 bytes) and as 2 x 2 x 4 (32 bytes).
  ScalarVolume v = ScalarVolume::allocate({2, 2, 2}, ScalarType::kInt16);
  NrrdWriteOptions o;
  o.encoding = NrrdEncoding::kGzip;
  write_nrrd(dir.path() / "g.nhdr", v, o);
  const std::string packed = test::read_file(dir.path() / "g.raw.gz");
  write_bytes(dir.path() / "long.nrrd",
              "NRRD0004\ntype: int16\ndimension: 3\nsizes: 2 2 1\nendian: little\n"
              "encoding: gzip\n\n" +
                  packed);
  EXPECT_THAT(message_of([&] { (void)read_nrrd(dir.path() / "long.nrrd"); }), HasSubstr("inflate to more than"));
  write_bytes(dir.path() / "short.nrrd",
              "NRRD0004\ntype: int16\ndimension: 3\nsizes: 2 2 4\nendian: little\n"
              "encoding: gzip\n\n" +
                  packed);
  EXPECT_THAT(message_of([&] { (void)read_nrrd(dir.path() / "short.nrrd"); }), HasSubstr("inflate to 16 bytes"));
}

TEST(Nrrd, HeaderAndWindowNormalisationNeedAVlbFile) {
  const TempFolder dir;
  write_nrrd(dir.path() / "v.nrrd", sample_volume(ScalarType::kInt16));
  VolumeReadOptions o;
  o.norm = NormSource::kWindow;
  EXPECT_THAT(message_of([&] { (void)read_volume(dir.path() / "v.nrrd", o); }), HasSubstr("needs a VLB file"));
}

}  // namespace
}  // namespace meltlab::render
