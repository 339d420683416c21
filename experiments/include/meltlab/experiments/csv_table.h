#pragma once
// A CSV table built row by row from format strings and written atomically (the benchmark studies'
// tables: one header line, then one fmt-formatted line per row).

#include <meltlab/core/atomic_file.h>

#include <fmt/format.h>

#include <filesystem>
#include <string>
#include <utility>

namespace meltlab::experiments {

class CsvTable {
 public:
  explicit CsvTable(std::string header) : text_(std::move(header) + "\n") {}
  /// One row: `fmt_text` with the values (fmt syntax, "{:.3f}").
  template <class... A>
  void row(const std::string& fmt_text, A&&... a) {
    text_ += fmt::format(fmt::runtime(fmt_text), std::forward<A>(a)...) + "\n";
  }
  void write(const std::filesystem::path& file) const { write_text_atomically(file, text_); }

 private:
  std::string text_;
};

}  // namespace meltlab::experiments
