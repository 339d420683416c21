// Mass / volume time series from CSV (observations.h).
//
// Format: comma-separated; the first non-blank line is the header. It must name exactly two
// columns, in any order: `time_s` and one of mass_kg, mass_g, volume_m3, volume_cm3. Any
// other column is an error naming it (a stray column is more likely a mistake than
// something to ignore, and two quantities would be ambiguous). Cells may be surrounded by
// spaces; blank lines and lines starting with '#' are skipped; a UTF-8 BOM and CRLF line
// ends are accepted. Every row needs both cells as finite numbers; time strictly
// increases; at least one row. Values are not range-checked (a tared scale can read a
// little below zero).

#include <meltlab/core/input_file.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/observations.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace meltlab::verify {

namespace fs = std::filesystem;

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split_cells(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return cells;
}

bool skipped(std::string_view line) {
  const std::string_view t = trim(line);
  return t.empty() || t.front() == '#';
}

}  // namespace

TimeSeries read_time_series(const fs::path& csv) {
  const std::string file = csv.string();
  std::error_code ec;
  if (fs::is_directory(csv, ec)) throw InputError(fmt::format("{}: is a directory, not a CSV file", file));
  std::istringstream in(read_text_file(csv, "CSV"));

  static const std::array<const char*, 4> kQuantities = {"mass_kg", "mass_g", "volume_m3", "volume_cm3"};
  TimeSeries ts;
  ts.file = csv;
  int time_col = -1, value_col = -1;
  std::size_t columns = 0;
  bool have_header = false;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::string_view view(line);
    if (line_no == 1 && view.substr(0, 3) == "\xEF\xBB\xBF") view.remove_prefix(3);
    if (skipped(view)) continue;
    const std::vector<std::string_view> cells = split_cells(view);
    const std::string at = fmt::format("{}:{}", file, line_no);
    if (!have_header) {
      for (std::size_t i = 0; i < cells.size(); ++i) {
        const std::string name(cells[i]);
        if (name == "time_s") {
          if (time_col >= 0) throw InputError(fmt::format("{}: column 'time_s' appears twice", at));
          time_col = static_cast<int>(i);
        } else if (std::find(kQuantities.begin(), kQuantities.end(), name) != kQuantities.end()) {
          if (value_col >= 0) {
            throw InputError(fmt::format("{}: two quantity columns ('{}' and '{}'); give one", at, ts.quantity, name));
          }
          value_col = static_cast<int>(i);
          ts.quantity = name;
        } else {
          throw InputError(
              fmt::format("{}: unknown column '{}' (expected time_s and one of mass_kg, mass_g, "
                          "volume_m3, volume_cm3)",
                          at, name));
        }
      }
      if (time_col < 0) throw InputError(fmt::format("{}: header has no 'time_s' column", at));
      if (value_col < 0) {
        throw InputError(
            fmt::format("{}: header has no quantity column (mass_kg, mass_g, volume_m3 or volume_cm3)", at));
      }
      columns = cells.size();
      have_header = true;
      continue;
    }
    if (cells.size() != columns) {
      throw InputError(fmt::format("{}: {} cells, the header has {} columns", at, cells.size(), columns));
    }
    const auto number = [&](int col) {
      const std::string_view cell = cells[static_cast<std::size_t>(col)];
      const char* name = col == time_col ? "time_s" : ts.quantity.c_str();
      if (cell.empty()) throw InputError(fmt::format("{}: empty cell for '{}'", at, name));
      double x = 0;
      const char* begin = cell.data();
      const char* end = cell.data() + cell.size();
      if (*begin == '+') ++begin;
      const auto [ptr, err] = std::from_chars(begin, end, x);
      if (err != std::errc() || ptr != end) {
        throw InputError(fmt::format("{}: '{}' is not a number (column '{}')", at, std::string(cell), name));
      }
      if (!std::isfinite(x)) {
        throw InputError(fmt::format("{}: '{}' is not a finite number (column '{}')", at, std::string(cell), name));
      }
      return x;
    };
    const double t = number(time_col);
    const double v = number(value_col);
    if (!ts.time_s.empty() && !(t > ts.time_s.back())) {
      throw InputError(fmt::format("{}: time_s {} does not increase (previous row: {})", at, t, ts.time_s.back()));
    }
    ts.time_s.push_back(t);
    ts.value.push_back(v);
    ts.line.push_back(line_no);
  }
  if (in.bad()) throw InputError(fmt::format("{}: read error", file));
  if (!have_header) throw InputError(fmt::format("{}:{}: empty file (no header line)", file, std::max(line_no, 1)));
  if (ts.time_s.empty()) throw InputError(fmt::format("{}:{}: no data rows after the header", file, line_no));
  return ts;
}

}  // namespace meltlab::verify
