#pragma once
// The observation tests use the shared file fixtures (tests/support/test_files.h).

#include "test_files.h"

namespace meltlab::verify::test {

using TempDir = meltlab::test::TempFolder;
using meltlab::test::read_file;
using meltlab::test::write_file;

}  // namespace meltlab::verify::test
