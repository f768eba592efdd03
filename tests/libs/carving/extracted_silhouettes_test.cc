// The hierarchical search on silhouettes as the extractor makes them (with
// their bounding boxes, which the summed-area tables then trust) gives the
// full scan's voxels exactly.
#include <gtest/gtest.h>

#include "libs/carving/carver.h"
#include "libs/sim/scene_generators.h"

namespace shapesense {
namespace {

TEST(ExtractedSilhouettesTest, HierarchicalEqualsFullScanOnRenderedScenes) {
  SyntheticRigOptions rig_options;
  rig_options.seed = 5;
  const Rig rig = MakeSyntheticRig(rig_options);
  CarvingOptions options;
  options.voxel_size = 2.0;
  const Carver carver(rig, options);
  const SilhouetteExtractor extractor{SilhouetteOptions{}};
  for (uint32_t seed = 0; seed < 3; ++seed) {
    const std::vector<RenderedView> views =
        RenderScene(rig, RandomScene(rig, 40 + seed, 2.6, 3), RenderOptions{}, seed);
    std::vector<Silhouette> silhouettes(views.size());
    for (size_t c = 0; c < views.size(); ++c) {
      extractor.Extract(views[c].image, views[c].background, &silhouettes[c]);
      ASSERT_GT(silhouettes[c].area, 0);
    }
    VoxelCloud full, hierarchical;
    carver.CarveFullScan(silhouettes, &full);
    carver.CarveHierarchical(silhouettes, &hierarchical);
    ASSERT_FALSE(full.voxels.empty());
    EXPECT_EQ(hierarchical.voxels, full.voxels) << "scene " << seed;
    EXPECT_EQ(hierarchical.labels, full.labels) << "scene " << seed;
  }
}

}  // namespace
}  // namespace shapesense
