#include "libs/silhouette/run_components.h"

#include <bit>

namespace shapesense {
namespace {

// First pixel at or after `from` whose bit equals `value`; `width` if none.
int NextPixelWithValue(const uint64_t* row, int words, int width, int from, bool value) {
  int i = from >> 6;
  if (i >= words) return width;
  const uint64_t flip = value ? 0 : ~uint64_t{0};
  uint64_t word = (row[i] ^ flip) & (~uint64_t{0} << (from & 63));
  while (word == 0) {
    if (++i == words) return width;
    word = row[i] ^ flip;
  }
  const int x = 64 * i + std::countr_zero(word);
  return x < width ? x : width;
}

// Union by the smaller index, so a root is the first run of its component in
// raster order and parent[i] <= i always.
int FindRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

void Unite(std::vector<int>& parent, int a, int b) {
  const int root_a = FindRoot(parent, a);
  const int root_b = FindRoot(parent, b);
  if (root_a < root_b) parent[root_b] = root_a;
  if (root_b < root_a) parent[root_a] = root_b;
}

// Joins each run of a row with the runs of the row above that it touches,
// diagonals included (8-connectivity): [a0, a1) and [b0, b1) touch when
// a0 <= b1 and b0 <= a1.
void UniteAdjacentRows(const std::vector<RowRun>& runs, int above_begin, int above_end, int begin,
                       int end, std::vector<int>& parent) {
  int above = above_begin;
  int here = begin;
  while (above < above_end && here < end) {
    const RowRun& a = runs[above];
    const RowRun& b = runs[here];
    if (a.x0 <= b.x1 && b.x0 <= a.x1) Unite(parent, above, here);
    if (a.x1 < b.x1) {
      ++above;
    } else {
      ++here;
    }
  }
}

}  // namespace

void ExtractRuns(const BitMask& mask, RunImage* out) {
  out->runs.clear();
  out->row_begin.assign(static_cast<size_t>(mask.height()) + 1, 0);
  const int width = mask.width();
  const int words = mask.words_per_row();
  for (int y = 0; y < mask.height(); ++y) {
    out->row_begin[y] = static_cast<int>(out->runs.size());
    const uint64_t* row = mask.Row(y);
    int x = NextPixelWithValue(row, words, width, 0, true);
    while (x < width) {
      const int end = NextPixelWithValue(row, words, width, x, false);
      out->runs.push_back({y, x, end});
      x = NextPixelWithValue(row, words, width, end, true);
    }
  }
  out->row_begin[mask.height()] = static_cast<int>(out->runs.size());
}

void KeepManipulatorComponents(const RunImage& image, int64_t min_area, ComponentScratch* scratch,
                               std::vector<RowRun>* kept) {
  const std::vector<RowRun>& runs = image.runs;
  const int count = static_cast<int>(runs.size());
  std::vector<int>& parent = scratch->parent;
  parent.resize(count);
  for (int i = 0; i < count; ++i) parent[i] = i;
  for (size_t y = 1; y + 1 < image.row_begin.size(); ++y) {
    UniteAdjacentRows(runs, image.row_begin[y - 1], image.row_begin[y], image.row_begin[y],
                      image.row_begin[y + 1], parent);
  }
  // parent[i] <= i, so one ascending pass resolves every run to its root.
  std::vector<int64_t>& area = scratch->area;
  area.assign(count, 0);
  int largest = -1;
  for (int i = 0; i < count; ++i) {
    parent[i] = parent[parent[i]];
    area[parent[i]] += runs[i].x1 - runs[i].x0;
  }
  for (int i = 0; i < count; ++i) {
    if (parent[i] == i && (largest < 0 || area[i] > area[largest])) largest = i;
  }
  kept->clear();
  for (int i = 0; i < count; ++i) {
    if (parent[i] == largest || area[parent[i]] >= min_area) kept->push_back(runs[i]);
  }
}

}  // namespace shapesense
