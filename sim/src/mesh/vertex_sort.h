#pragma once
// Private to sim/src/mesh: sorting per-edge and per-corner records by vertex index in O(n).
//
// The topology check pairs the directed edges of a mesh by sorting them on their (lo, hi)
// vertex pair and groups corners by vertex. Vertex indices are slots in [0, n_slots), so a stable
// counting sort by hi and then by lo gives the same order as a comparison sort on (lo, hi)
// with ties in insertion order, in two linear passes instead of O(n log n) comparisons.

#include <meltlab/sim/mesh.h>

#include <cstddef>
#include <vector>

namespace meltlab::sim {

/// Stable counting sort of `items` by key(item) in [0, n_keys); `scratch` is reused.
template <class T, class Key>
void counting_sort_by(std::vector<T>& items, std::vector<T>& scratch, std::size_t n_keys, Key key) {
  std::vector<std::size_t> start(n_keys + 1, 0);
  for (const T& x : items) ++start[static_cast<std::size_t>(key(x)) + 1];
  for (std::size_t k = 0; k < n_keys; ++k) start[k + 1] += start[k];
  scratch.resize(items.size());
  for (const T& x : items) scratch[start[static_cast<std::size_t>(key(x))]++] = x;
  items.swap(scratch);
}

/// Sorts records whose `key` field is (lo << 32) | hi, lo and hi vertex slots < n_slots, by
/// key; records with equal keys keep their order (stable).
template <class T>
void sort_by_vertex_pair(std::vector<T>& items, std::size_t n_slots) {
  std::vector<T> scratch;
  counting_sort_by(items, scratch, n_slots, [](const T& x) { return x.key & 0xffffffffu; });
  counting_sort_by(items, scratch, n_slots, [](const T& x) { return x.key >> 32; });
}

}  // namespace meltlab::sim
