#include "libs/carving/carver.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "libs/carving/summed_area.h"
#include "libs/carving/voxel_table.h"
#include "libs/core/error.h"

namespace shapesense {

using carving_detail::BlockLevel;
using carving_detail::PixelRect;
using carving_detail::SummedAreaTable;
using carving_detail::VoxelTable;

namespace {

// One frame-set's silhouettes, checked, with raw pointers for the inner loops.
struct Frame {
  std::vector<cv::Mat> masks;                // continuous
  std::vector<cv::Mat> labels;               // continuous, or empty (no markers)
  std::vector<const uint8_t*> mask_pixels;   // masks[c].data
  std::vector<cv::Rect> mask_bounds;         // Silhouette::bounds, empty when not known
  std::vector<const uint8_t*> label_pixels;  // labels[c].data, nullptr when empty
};

// A continuous CV_8UC1 image of the camera's size (continuous so that a
// table pixel index y * width + x addresses it directly).
cv::Mat CheckedImage(const cv::Mat& image, const Camera& camera, const std::string& what) {
  if (image.type() != CV_8UC1 || image.cols != camera.width || image.rows != camera.height) {
    std::ostringstream text;
    text << what << " of camera '" << camera.name << "' must be CV_8UC1 of " << camera.width << "x"
         << camera.height << ", got type " << image.type() << " of " << image.cols << "x"
         << image.rows;
    throw std::invalid_argument(text.str());
  }
  return image.isContinuous() ? image : image.clone();
}

Frame CheckedFrame(const std::vector<Silhouette>& silhouettes, const std::vector<Camera>& cameras) {
  if (silhouettes.size() != cameras.size()) {
    throw std::invalid_argument("carving: expected one silhouette per camera (" +
                                std::to_string(cameras.size()) + "), got " +
                                std::to_string(silhouettes.size()));
  }
  Frame frame;
  for (size_t c = 0; c < cameras.size(); ++c) {
    frame.masks.push_back(CheckedImage(silhouettes[c].mask, cameras[c], "mask"));
    frame.mask_pixels.push_back(frame.masks.back().data);
    // The extractor already knows each mask's bounding box (area > 0); a
    // hand-built silhouette leaves it empty and the sums scan for it.
    frame.mask_bounds.push_back(silhouettes[c].area > 0 ? silhouettes[c].bounds : cv::Rect());
    const cv::Mat& labels = silhouettes[c].labels;
    frame.labels.push_back(labels.empty() ? labels : CheckedImage(labels, cameras[c], "labels"));
    frame.label_pixels.push_back(labels.empty() ? nullptr : frame.labels.back().data);
  }
  return frame;
}

// The voxel test of the reference: inside the silhouette in every camera.
inline bool InAllSilhouettes(const uint32_t* pixels, const uint8_t* const* masks, int num_cameras) {
  for (int c = 0; c < num_cameras; ++c) {
    if (pixels[c] == VoxelTable::kOutside || masks[c][pixels[c]] == 0) return false;
  }
  return true;
}

uint8_t VoxelLabel(const uint32_t* pixels, const Frame& frame, int min_marker_views) {
  const int num_cameras = static_cast<int>(frame.label_pixels.size());
  int marker_views = 0;
  // Stops as soon as the count is decided: label images are read nowhere
  // else, so each read here is likely a cache miss.
  for (int c = 0; c < num_cameras && marker_views + num_cameras - c >= min_marker_views; ++c) {
    const uint8_t* labels = frame.label_pixels[c];
    if (labels != nullptr && labels[pixels[c]] == kLabelMarker) {
      if (++marker_views >= min_marker_views) return kLabelMarker;
    }
  }
  return kLabelBody;
}

// LSD radix sort, a byte at a time, of keys on their bits [8, 8 + index_bits):
// a few passes over a few thousand keys cost less than a comparison sort.
void SortKeysByVoxelIndex(std::vector<uint64_t>* keys, int index_bits) {
  std::vector<uint64_t> sorted(keys->size());
  for (int shift = 8; shift < 8 + index_bits; shift += 8) {
    std::array<size_t, 257> offsets{};
    for (const uint64_t key : *keys) ++offsets[((key >> shift) & 0xff) + 1];
    for (size_t digit = 1; digit < offsets.size(); ++digit) offsets[digit] += offsets[digit - 1];
    for (const uint64_t key : *keys) sorted[offsets[(key >> shift) & 0xff]++] = key;
    keys->swap(sorted);
  }
}

// Labels the occupied slots and writes them in ascending voxel index.
void WriteCloud(const VoxelTable& table, const VoxelGrid& grid, const Frame& frame,
                int min_marker_views, const std::vector<uint32_t>& slots, VoxelCloud* out) {
  // Key: voxel index above, label in the low byte.
  std::vector<uint64_t> keys(slots.size());
  for (size_t i = 0; i < slots.size(); ++i) {
    const uint32_t* pixels = table.Pixels(slots[i]);
    keys[i] = (static_cast<uint64_t>(table.LinearIndex(slots[i])) << 8) |
              VoxelLabel(pixels, frame, min_marker_views);
  }
  SortKeysByVoxelIndex(&keys, std::bit_width(static_cast<uint64_t>(grid.NumVoxels() - 1)));
  out->grid = grid;
  out->voxels.resize(keys.size());
  out->labels.resize(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    out->voxels[i] = static_cast<int32_t>(keys[i] >> 8);
    out->labels[i] = static_cast<uint8_t>(keys[i] & 0xff);
  }
}

// Coarse-to-fine search over the table's blocks. A block is empty when its
// pixel bounds hold no silhouette pixel in some camera, full when they are
// all silhouette in every camera and no voxel is outside an image; otherwise
// its children are searched, and at the leaf level its voxels are tested.
class HierarchicalSearch {
 public:
  HierarchicalSearch(const VoxelTable& table, const Frame& frame)
      : table_(table), frame_(frame), counts_(table.num_cameras()), order_(table.num_cameras()) {
    for (size_t c = 0; c < frame.masks.size(); ++c) {
      sums_.emplace_back(frame.masks[c], frame.mask_bounds[c]);
    }
  }

  std::vector<uint32_t> Run() {
    for (int64_t block = 0; block < table_.num_coarse_blocks(); ++block) Visit(0, block);
    return std::move(occupied_);
  }

 private:
  enum class Verdict { kEmpty, kFull, kMixed };

  // Leaves counts_[c]: silhouette pixels in the block's bounds in camera c.
  Verdict Classify(const BlockLevel& level, int64_t block) {
    const int num_cameras = table_.num_cameras();
    const PixelRect* rects = level.rects.data() + block * num_cameras;
    bool full = level.any_outside[block] == 0;
    for (int c = 0; c < num_cameras; ++c) {
      counts_[c] = sums_[c].Count(rects[c]);
      if (counts_[c] == 0) return Verdict::kEmpty;
      full = full && counts_[c] == rects[c].Area();
    }
    return full ? Verdict::kFull : Verdict::kMixed;
  }

  void Visit(size_t level_index, int64_t block) {
    const BlockLevel& level = table_.levels()[level_index];
    const Verdict verdict = Classify(level, block);
    if (verdict == Verdict::kEmpty) return;
    const int64_t voxels = int64_t{level.edge} * level.edge * level.edge;
    if (verdict == Verdict::kFull) {
      for (int64_t slot = block * voxels; slot < (block + 1) * voxels; ++slot) Add(slot);
    } else if (level_index + 1 != table_.levels().size()) {
      for (int64_t child = 8 * block; child < 8 * block + 8; ++child) Visit(level_index + 1, child);
    } else if (level.any_outside[block] != 0) {
      TestVoxelsNearImageBorders(block * voxels, (block + 1) * voxels);
    } else {
      TestVoxels(level, block, block * voxels, (block + 1) * voxels);
    }
  }

  // The usual leaf: every voxel is inside every image. Cameras in which the
  // block's bounds are entirely silhouette cannot reject a voxel and are
  // skipped; the emptiest camera goes first. Branch-free, since about half of
  // the voxels tested here are occupied.
  void TestVoxels(const BlockLevel& leaf, int64_t block, int64_t first_slot, int64_t end_slot) {
    const int num_cameras = table_.num_cameras();
    const PixelRect* rects = leaf.rects.data() + block * num_cameras;
    int tested = 0;
    for (int c = 0; c < num_cameras; ++c) {
      if (counts_[c] != rects[c].Area()) order_[tested++] = c;
    }
    std::sort(order_.begin(), order_.begin() + tested, [&](int a, int b) {
      return int64_t{counts_[a]} * rects[b].Area() < int64_t{counts_[b]} * rects[a].Area();
    });
    size_t size = occupied_.size();
    occupied_.resize(size + static_cast<size_t>(end_slot - first_slot));
    for (int64_t slot = first_slot; slot < end_slot; ++slot) {
      const uint32_t* pixels = table_.Pixels(slot);
      bool inside = true;
      for (int i = 0; i < tested; ++i) {
        inside &= frame_.mask_pixels[order_[i]][pixels[order_[i]]] != 0;
      }
      occupied_[size] = static_cast<uint32_t>(slot);
      size += inside ? 1 : 0;
    }
    occupied_.resize(size);
  }

  void TestVoxelsNearImageBorders(int64_t first_slot, int64_t end_slot) {
    const int num_cameras = table_.num_cameras();
    for (int64_t slot = first_slot; slot < end_slot; ++slot) {
      if (InAllSilhouettes(table_.Pixels(slot), frame_.mask_pixels.data(), num_cameras)) Add(slot);
    }
  }

  void Add(int64_t slot) { occupied_.push_back(static_cast<uint32_t>(slot)); }

  const VoxelTable& table_;
  const Frame& frame_;
  std::vector<SummedAreaTable> sums_;
  std::vector<int32_t> counts_;  // per camera, of the block last classified
  std::vector<int> order_;       // cameras to test at a leaf
  std::vector<uint32_t> occupied_;
};

}  // namespace

std::string CarvingOptions::Validate() const {
  if (!(voxel_size > 0.0) || !std::isfinite(voxel_size)) {
    return Expected("voxel_size", "a positive number", voxel_size);
  }
  if (min_marker_views < 1) {
    return Expected("min_marker_views", "an integer >= 1", min_marker_views);
  }
  if (coarse_block < 2 || coarse_block > 64 ||
      !std::has_single_bit(static_cast<unsigned>(coarse_block))) {
    return Expected("coarse_block", "a power of 2 from 2 to 64", coarse_block);
  }
  return {};
}

struct Carver::Impl {
  Impl(const Rig& rig, const CarvingOptions& carving, const ProgressCallback& progress)
      : options(carving),
        cameras(rig.cameras),
        grid(VoxelGrid::Covering(rig.workspace_min, rig.workspace_max, carving.voxel_size)),
        table(grid, cameras, carving.coarse_block, progress) {}

  CarvingOptions options;
  std::vector<Camera> cameras;
  VoxelGrid grid;
  VoxelTable table;
};

namespace {

const Rig& ValidatedRig(const Rig& rig, const CarvingOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("carving options: " + error);
  }
  if (const std::string error = rig.Validate(); !error.empty()) {
    throw std::invalid_argument("rig: " + error);
  }
  return rig;
}

}  // namespace

Carver::Carver(const Rig& rig, const CarvingOptions& options, const ProgressCallback& progress)
    : impl_(std::make_unique<Impl>(ValidatedRig(rig, options), options, progress)) {}

Carver::~Carver() = default;

void Carver::CarveFullScan(const std::vector<Silhouette>& silhouettes, VoxelCloud* out) const {
  const Frame frame = CheckedFrame(silhouettes, impl_->cameras);
  const VoxelTable& table = impl_->table;
  std::vector<uint32_t> occupied;
  for (int64_t slot = 0; slot < table.num_slots(); ++slot) {
    if (InAllSilhouettes(table.Pixels(slot), frame.mask_pixels.data(), table.num_cameras())) {
      occupied.push_back(static_cast<uint32_t>(slot));
    }
  }
  WriteCloud(table, impl_->grid, frame, impl_->options.min_marker_views, occupied, out);
}

void Carver::CarveHierarchical(const std::vector<Silhouette>& silhouettes, VoxelCloud* out) const {
  const Frame frame = CheckedFrame(silhouettes, impl_->cameras);
  const std::vector<uint32_t> occupied = HierarchicalSearch(impl_->table, frame).Run();
  WriteCloud(impl_->table, impl_->grid, frame, impl_->options.min_marker_views, occupied, out);
}

const VoxelGrid& Carver::grid() const { return impl_->grid; }

size_t Carver::MemoryBytes() const { return impl_->table.MemoryBytes(); }

}  // namespace shapesense
