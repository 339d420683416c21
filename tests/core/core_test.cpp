// core/: the limits, the run folder protocol, the content hash, checked input reading, image
// headers and one-line errors. Each expectation is a hand-computed value or a protocol rule
// that a wrong implementation breaks.

#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>
#include <meltlab/core/image_header.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>
#include <meltlab/core/run_folder.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>

#include "test_files.h"

namespace meltlab {
namespace {

namespace fs = std::filesystem;
using test::message_of;
using test::png_header;
using test::TempFolder;
using test::write_file;
using ::testing::HasSubstr;
using ::testing::Not;

// ---- errors ----

TEST(OneLine, JoinsLinesAndDropsTrailingBlanks) {
  EXPECT_EQ(one_line("a\nb\r\n"), "a; b");
  EXPECT_EQ(one_line("a \nb"), "a b");
  EXPECT_EQ(one_line("\n\n"), "unknown error");
  EXPECT_EQ(std::string(InputError("file.off: bad\nsecond line").what()), "file.off: bad; second line");
}

// ---- limits ----

TEST(InputLimits, ParsesNamesAndScientificValuesOnTopOfABase) {
  const InputLimits base;
  const InputLimits l = parse_input_limits("mesh_elements=1e8,image_pixels=640", base, "--limits");
  EXPECT_EQ(l.mesh_elements, 100'000'000);
  EXPECT_EQ(l.image_pixels, 640);
  EXPECT_EQ(l.volume_samples, base.volume_samples);  // untouched names keep the base value
  EXPECT_EQ(l.text_bytes, base.text_bytes);
  // describe/parse round trip
  const InputLimits again = parse_input_limits(describe_input_limits(l), InputLimits{}, "x");
  EXPECT_EQ(again.mesh_elements, l.mesh_elements);
  EXPECT_EQ(again.image_pixels, l.image_pixels);
}

TEST(InputLimits, RefusesUnknownNamesAndBadValuesNamingTheOption) {
  for (const char* bad : {"teapots=3", "mesh_elements=", "mesh_elements=-1", "mesh_elements=0", "mesh_elements=x",
                          "mesh_elements=1e40", "image_pixels"}) {
    const std::string what = message_of([&] { parse_input_limits(bad, InputLimits{}, "MELTLAB_LIMITS"); });
    EXPECT_THAT(what, HasSubstr("MELTLAB_LIMITS")) << bad;
  }
}

TEST(InputLimits, CheckCountRefusesNegativeAndTooLargeCounts) {
  EXPECT_NO_THROW(check_count("m.off", "vertices", 10, 10, "mesh_elements"));
  EXPECT_THAT(message_of([] { check_count("m.off", "vertices", 11, 10, "mesh_elements"); }),
              HasSubstr("m.off: vertices 11 exceeds the limit of 10 (raise it with --limits mesh_elements=N)"));
  EXPECT_THAT(message_of([] { check_count("m.off", "vertices", -4, 10, "mesh_elements"); }),
              HasSubstr("m.off: vertices -4 is negative"));
}

TEST(InputLimits, CheckedMulDetectsOverflow) {
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  EXPECT_EQ(checked_mul(30000, 30000), 900'000'000);
  EXPECT_EQ(checked_mul(0, kMax), 0);
  EXPECT_EQ(checked_mul(kMax, 1), kMax);
  EXPECT_EQ(checked_mul(std::int64_t{1} << 32, std::int64_t{1} << 31), -1);
  EXPECT_EQ(checked_mul(-1, 5), -1);
}

// ---- content hash ----

TEST(ContentHash, IsFnv1a64) {
  // Reference values of FNV-1a 64 (Fowler/Noll/Vo test vectors).
  EXPECT_EQ(ContentHash().value(), 0xcbf29ce484222325ULL);
  EXPECT_EQ(ContentHash().add_bytes("a").value(), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(ContentHash().add_bytes("foobar").value(), 0x85944171f73967e8ULL);
  EXPECT_EQ(ContentHash().add_bytes("a").hex(), "af63dc4c8601ec8c");
  EXPECT_EQ(ContentHash().add_bytes("foo").add_bytes("bar").value(), ContentHash().add_bytes("foobar").value());
}

TEST(ContentHash, FieldsCannotCollideByConcatenation) {
  EXPECT_NE(ContentHash().add_field("ab").add_field("c").value(), ContentHash().add_field("a").add_field("bc").value());
}

TEST(ContentHash, FileHashIsTheHashOfTheBytes) {
  const TempFolder dir;
  write_file(dir.path() / "f", "foobar");
  EXPECT_EQ(file_hash(dir.path() / "f"), ContentHash().add_bytes("foobar").hex());
  EXPECT_THAT(message_of([&] { file_hash(dir.path() / "missing"); }), HasSubstr("missing"));
}

// ---- checked input reading ----

TEST(InputFile, ReadsTextAndRefusesWhatIsNotARegularReadableFile) {
  const TempFolder dir;
  write_file(dir.path() / "a.yaml", "x: 1\n");
  EXPECT_EQ(read_text_file(dir.path() / "a.yaml", "config"), "x: 1\n");
  EXPECT_THAT(message_of([&] { read_text_file(dir.path() / "no.yaml", "config"); }),
              HasSubstr((dir.path() / "no.yaml").string()));
  EXPECT_THAT(message_of([&] { read_text_file(dir.path(), "config"); }), HasSubstr(dir.path().string()));
}

TEST(InputFile, RefusesTextLargerThanTheLimit) {
  const TempFolder dir;
  write_file(dir.path() / "big.csv", std::string(2000, 'x'));
  const InputLimits saved = input_limits();
  InputLimits small = saved;
  small.text_bytes = 1000;
  set_input_limits(small);
  const std::string what = message_of([&] { read_text_file(dir.path() / "big.csv", "series"); });
  set_input_limits(saved);
  EXPECT_THAT(what, HasSubstr("big.csv"));
  EXPECT_THAT(what, HasSubstr("text_bytes"));
}

// ---- image headers ----

TEST(ImageHeader, ReadsPngSizeAndRefusesAHugeDeclaredImage) {
  const TempFolder dir;
  // 640 x 480 RGB at 8 bits: 921600 bytes of samples, which deflate packs into >= 450 bytes.
  write_file(dir.path() / "small.png", png_header(640, 480) + std::string(450, '\0'));
  const auto size = declared_image_size(dir.path() / "small.png");
  ASSERT_TRUE(size.has_value());
  EXPECT_EQ(size->width, 640);
  EXPECT_EQ(size->height, 480);
  EXPECT_EQ(size->sample_bytes, 640 * 480 * 3);
  EXPECT_NO_THROW(check_declared_image_size(dir.path() / "small.png"));
  // The same header alone: 33 bytes cannot hold the samples at any compression (2048:1 at most).
  write_file(dir.path() / "truncated.png", png_header(640, 480));
  const std::string truncated = message_of([&] { check_declared_image_size(dir.path() / "truncated.png"); });
  EXPECT_THAT(truncated, HasSubstr("truncated.png"));
  EXPECT_THAT(truncated, HasSubstr("at any compression"));
  write_file(dir.path() / "huge.png", png_header(30000, 30000));
  const std::string what = message_of([&] { check_declared_image_size(dir.path() / "huge.png"); });
  EXPECT_THAT(what, HasSubstr("huge.png"));
  EXPECT_THAT(what, HasSubstr("image_pixels"));
}

// ---- the run folder ----

TEST(RunFolder, StagesBesideTheTargetAndCommitsAtomically) {
  const TempFolder dir;
  const fs::path out = dir.path() / "runs" / "a";
  {
    RunFolder run(out, RunFolderOptions{"--out", "run.json", "run", false});
    EXPECT_NE(run.path(), out);
    EXPECT_EQ(run.path().parent_path(), out.parent_path());
    EXPECT_FALSE(fs::exists(out));  // nothing at --out until the run is complete
    write_file(run.path() / "run.json", "{}");
    run.commit();
    EXPECT_EQ(run.path(), out);
  }
  EXPECT_TRUE(fs::exists(out / "run.json"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path() / "runs"), fs::directory_iterator()), 1);
}

TEST(RunFolder, AFailedRunLeavesNothingNotEvenTheParentsItCreated) {
  const TempFolder dir;
  {
    RunFolder run(dir.path() / "new" / "deeper" / "a", RunFolderOptions{"--out", "run.json", "run", false});
    write_file(run.path() / "half.csv", "1,2");
  }  // no commit: an exception in the run
  EXPECT_FALSE(fs::exists(dir.path() / "new"));
}

TEST(RunFolder, RefusesAFinishedRunWithoutOverwriteAndReplacesItWith) {
  const TempFolder dir;
  const fs::path out = dir.path() / "a";
  fs::create_directories(out);
  write_file(out / "run.json", "old");
  EXPECT_THAT(message_of([&] {
                RunFolder(out, RunFolderOptions{"--out", "run.json", "run", false});
              }),
              HasSubstr("pass --overwrite"));
  RunFolder run(out, RunFolderOptions{"--out", "run.json", "run", true});
  write_file(run.path() / "run.json", "new");
  run.commit();
  EXPECT_EQ(read_text_file(out / "run.json", "run"), "new");
}

TEST(RunFolder, RefusesAFileInTheWayAndAForeignFolder) {
  const TempFolder dir;
  write_file(dir.path() / "file", "x");
  EXPECT_THAT(message_of([&] {
                RunFolder(dir.path() / "file", RunFolderOptions{"--out", "run.json", "run", true});
              }),
              HasSubstr("is not a folder"));
  fs::create_directories(dir.path() / "photos");
  write_file(dir.path() / "photos" / "img.png", "x");
  EXPECT_THAT(message_of([&] {
                RunFolder(dir.path() / "photos", RunFolderOptions{"--out", "run.json", "run", true});
              }),
              HasSubstr("not empty"));
  EXPECT_TRUE(fs::exists(dir.path() / "photos" / "img.png"));  // --overwrite never deletes foreign files
}

TEST(RunFolder, FileSystemRefusalsAreOneSentenceInputErrors) {
  const TempFolder dir;
  const std::string too_long(300, 'n');  // NAME_MAX is 255 on Linux file systems
  const std::string what = message_of([&] {
    RunFolder(dir.path() / too_long / "a", RunFolderOptions{"--out", "run.json", "run", false});
  });
  EXPECT_THAT(what, HasSubstr("--out"));
  EXPECT_THAT(what, HasSubstr("cannot"));
  EXPECT_THAT(what, Not(HasSubstr("filesystem error")));
  write_file(dir.path() / "plain", "x");
  EXPECT_THAT(message_of([&] {
                RunFolder(dir.path() / "plain" / "a", RunFolderOptions{"--out", "run.json", "run", false});
              }),
              HasSubstr("--out"));
}

}  // namespace
}  // namespace meltlab
