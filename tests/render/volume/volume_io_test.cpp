// Volume files (render/volume/volume_io.h, render/vdb/openvdb.h): round trips of every sample type
// and placement through the raw + JSON header and through OpenVDB, and headers and raw files that
// lie, refused with one line naming the file before anything is allocated.

#include <meltlab/core/error.h>
#include <meltlab/render/vdb/openvdb.h>
#include <meltlab/render/volume/generate.h>
#include <meltlab/render/volume/volume_io.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_files.h"

namespace meltlab::render {
namespace {

using test::message_of;
using test::read_file;
using test::TempFolder;
using test::write_file;
using ::testing::HasSubstr;
using Vec3 = Eigen::Vector3d;

Volume sphere_turbulence(SampleType type) {
  VolumeGenerateOptions g;
  g.kind = VolumeKind::kTurbulenceSphere;
  g.nx = 12, g.ny = 10, g.nz = 9;
  g.storage = type;
  Volume v = generate_volume(g);
  v.fit_to_box(Box3{Vec3(-3, -2, 0), Vec3(9, 8, 4.5)});
  return v;
}

void expect_same(const Volume& a, const Volume& b) {
  ASSERT_EQ(a.dims(), b.dims());
  EXPECT_EQ(a.type(), b.type());
  EXPECT_EQ(a.placement(), b.placement());
  EXPECT_TRUE(a.origin().isApprox(b.origin(), 1e-12));
  EXPECT_TRUE(a.spacing().isApprox(b.spacing(), 1e-12));
  for (int k = 0; k < a.nz(); ++k)
    for (int j = 0; j < a.ny(); ++j)
      for (int i = 0; i < a.nx(); ++i) ASSERT_EQ(a.value(i, j, k), b.value(i, j, k)) << i << " " << j << " " << k;
}

TEST(VolumeIo, RawAndHeaderRoundTripEverySampleType) {
  const TempFolder dir;
  for (auto type : {SampleType::kFloat32, SampleType::kUint8, SampleType::kUint16}) {
    Volume v = sphere_turbulence(type);
    if (type == SampleType::kUint16) v.set_placement(SamplePlacement::kNodes);
    const auto header = dir.path() / ("v_" + sample_type_name(type) + ".json");
    write_volume(header, v, {{"kind", "turbulence_sphere"}, {"octaves", "4"}});
    const Volume r = read_volume(header);
    expect_same(v, r);
    EXPECT_EQ(volume_content_hash(v), volume_content_hash(r));
    EXPECT_THAT(read_file(header), HasSubstr("\"octaves\": 4.0"));
  }
}

TEST(VolumeIo, OpenVdbRoundTripKeepsValuesAndPlacement) {
  const TempFolder dir;
  const Volume v = sphere_turbulence(SampleType::kFloat32);
  write_vdb(dir.path() / "v.vdb", v);
  const Volume r = read_volume(dir.path() / "v.vdb");
  // The .vdb holds the active (non-zero) voxels: its bounding box may be smaller than the volume
  // when border planes are zero; compare values where both are defined.
  for (int k = 0; k < r.nz(); ++k)
    for (int j = 0; j < r.ny(); ++j)
      for (int i = 0; i < r.nx(); ++i) {
        const Vec3 p = r.world_from_index(Vec3(i, j, k));
        const Vec3 g = v.index_from_world(p);
        const int a = int(std::lround(g.x())), b = int(std::lround(g.y())), c = int(std::lround(g.z()));
        ASSERT_NEAR(g.x(), a, 1e-9);
        ASSERT_EQ(r.value(i, j, k), v.value(a, b, c)) << i << " " << j << " " << k << " -> " << a << " " << b << " "
                                                      << c << " dims " << r.nx() << " " << r.ny() << " " << r.nz();
      }
  EXPECT_EQ(r.placement(), SamplePlacement::kCellCentred);
  EXPECT_TRUE(r.spacing().isApprox(v.spacing(), 1e-12));
  const OpenVdbPeer peer(v);
  std::int64_t non_zero = 0;
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) non_zero += v.value(i, j, k) != 0.0f;
  EXPECT_EQ(peer.active_voxels(), non_zero);
}

std::string header_text(const std::string& dims, const std::string& extra = "", const std::string& type = "uint8") {
  return "{\"format\": \"meltlab-volume\", \"version\": 1, \"dims\": " + dims + ", \"sample_type\": \"" + type +
         "\", \"data\": \"v.raw\"" + extra + "}\n";
}

TEST(VolumeIo, RefusesHeadersAndRawFilesThatLie) {
  const TempFolder dir;
  const auto h = dir.path() / "v.json";
  write_file(dir.path() / "v.raw", std::string(24, '\1'));
  auto refused = [&](const std::string& header, const std::string& expect) {
    write_file(h, header);
    const std::string what = message_of([&] { (void)read_volume(h); });
    EXPECT_THAT(what, HasSubstr(expect)) << header;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  };
  write_file(h, header_text("[2, 3, 4]"));
  EXPECT_NO_THROW((void)read_volume(h));
  refused(header_text("[2, 3, 5]"), "holds 24 bytes");                             // lying size
  refused(header_text("[2, 3, 4]", "", "float32"), "declares 2 x 3 x 4 float32");  // wrong type
  refused(header_text("[0, 3, 4]"), "'dims' must be three whole numbers >= 1");
  refused(header_text("[-2, 3, 4]"), "'dims' must be three whole numbers >= 1");
  refused(header_text("[2147483647, 2147483647, 2147483647]"), "overflow");  // no allocation attempted
  refused(header_text("[4096, 4096, 1024]"), "volume_samples");
  refused(header_text("[2, 3, 4]", ", \"colour\": 1"), "unknown key 'colour'");
  refused(header_text("[2, 3, 4]", ", \"content_hash\": \"0123456789abcdef\""), "content_hash");
  refused(header_text("[2, 3]"), "dims");
  refused("{\"format\": \"png\", \"version\": 1}", "not a meltlab volume header");
  refused(header_text("[2, 3, 4]").replace(header_text("[2, 3, 4]").find("v.raw"), 5, "w.raw"), "no such file");
  refused("{\"format\": [", "v.json:1");
  write_file(dir.path() / "bad.vdb", "not a vdb file at all");
  EXPECT_THAT(message_of([&] { (void)read_volume(dir.path() / "bad.vdb"); }), HasSubstr("bad.vdb"));
}

TEST(VolumeIo, RefusesNonFiniteFloatSamples) {
  const TempFolder dir;
  const float bad[2] = {1.0f, std::numeric_limits<float>::quiet_NaN()};
  write_file(dir.path() / "v.raw", std::string(reinterpret_cast<const char*>(bad), sizeof bad));
  write_file(dir.path() / "v.json", header_text("[2, 1, 1]", "", "float32"));
  EXPECT_THAT(message_of([&] { (void)read_volume(dir.path() / "v.json"); }), HasSubstr("not a finite number"));
}

}  // namespace
}  // namespace meltlab::render
