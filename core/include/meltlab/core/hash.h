#pragma once
// The one content hash of meltlab: 64-bit FNV-1a over bytes. It names generated files,
// records which input a run read and decides whether a finished experiment can be reused.
// Not cryptographic: it detects changed inputs, not adversaries.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace meltlab {

class ContentHash {
 public:
  /// Adds raw bytes (hash(a) then hash(b) equals hash of a + b).
  ContentHash& add_bytes(std::string_view bytes) {
    for (const unsigned char c : bytes) h_ = (h_ ^ c) * kPrime;
    return *this;
  }
  /// Adds one field of a record: its bytes and then its length, so that the concatenation of
  /// fields cannot collide ("ab","c" differs from "a","bc").
  ContentHash& add_field(std::string_view bytes);
  /// Adds the bytes of a file. Throws InputError naming the file if it cannot be read.
  ContentHash& add_file(const std::filesystem::path& file);

  std::uint64_t value() const { return h_; }
  /// 16 lower-case hex digits.
  std::string hex() const;

 private:
  static constexpr std::uint64_t kOffset = 0xcbf29ce484222325ULL;
  static constexpr std::uint64_t kPrime = 0x100000001b3ULL;
  std::uint64_t h_ = kOffset;
};

/// SplitMix64's mixing step: a counter-based pseudo-random 64-bit value of x (no shared state), for
/// jitter, noise and seeds that must come out the same serial and parallel.
constexpr std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

/// A uniform number in (0, 1) from 64 random bits (the top 53, centred in their interval).
constexpr double unit_from_bits(std::uint64_t bits) {
  return (static_cast<double>(bits >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

/// FNV-1a 64 of a file's bytes as 16 hex digits.
std::string file_hash(const std::filesystem::path& file);
/// FNV-1a 64 of a string as 16 hex digits.
std::string text_hash(std::string_view text);

}  // namespace meltlab
