// The carving service's prepared views: found by the image's identity only,
// bounded, and their buffers recycled.
#include "services/carving/prepared_views.h"

#include <gtest/gtest.h>

namespace shapesense {
namespace {

image_t Image(int64_t trigger_seq, int64_t frame_id) {
  image_t image{};
  image.trigger_seq = trigger_seq;
  image.trigger_utime = 1000 * trigger_seq;
  image.frame_id = frame_id;
  image.device_timestamp_ns = 7 * frame_id;
  return image;
}

// A view told apart by its end time.
PreparedView View(int64_t end_utime) {
  PreparedView view;
  view.end_utime = end_utime;
  return view;
}

FrameSet Set(std::vector<image_t> images) {
  FrameSet set;
  set.trigger_seq = images[0].trigger_seq;
  set.images = std::move(images);
  return set;
}

TEST(PreparedViewsTest, ASetTakesTheViewsOfItsOwnImagesInRigOrder) {
  PreparedViews views(8);
  views.Keep(IdentityOf(1, Image(5, 51)), View(2));
  views.Keep(IdentityOf(0, Image(5, 50)), View(1));
  views.Keep(IdentityOf(0, Image(6, 60)), View(3));
  const std::vector<PreparedView> taken = views.Take(Set({Image(5, 50), Image(5, 51)}));
  ASSERT_EQ(taken.size(), 2u);
  EXPECT_EQ(taken[0].end_utime, 1);
  EXPECT_EQ(taken[1].end_utime, 2);
  EXPECT_EQ(views.size(), 1u) << "set 6's view stays";
}

TEST(PreparedViewsTest, AViewOfAnotherImageIsNeverUsed) {
  PreparedViews views(8);
  views.Keep(IdentityOf(0, Image(5, 50)), View(1));
  image_t other_frame = Image(5, 49);  // same trigger, another exposure
  image_t other_time = Image(5, 50);
  other_time.device_timestamp_ns += 1;
  image_t other_camera = Image(5, 50);
  for (const FrameSet& set : {Set({other_frame}), Set({other_time}), Set({Image(6, 50)})}) {
    EXPECT_EQ(views.Take(set)[0].end_utime, 0) << "prepared again by the carving";
  }
  EXPECT_EQ(views.Take(Set({Image(9, 1), other_camera}))[1].end_utime, 0)
      << "camera 1's image, camera 0's view";
  EXPECT_EQ(views.Take(Set({Image(5, 50)}))[0].end_utime, 1);
}

TEST(PreparedViewsTest, KeepingTheSameIdentityReplacesAndTheOldestGoesBeyondCapacity) {
  PreparedViews views(2);
  views.Keep(IdentityOf(0, Image(1, 10)), View(1));
  views.Keep(IdentityOf(0, Image(1, 10)), View(2));
  EXPECT_EQ(views.size(), 1u);
  views.Keep(IdentityOf(0, Image(2, 20)), View(3));
  views.Keep(IdentityOf(0, Image(3, 30)), View(4));
  EXPECT_EQ(views.size(), 2u);
  EXPECT_EQ(views.Take(Set({Image(1, 10)}))[0].end_utime, 0) << "the oldest went";
  EXPECT_EQ(views.Take(Set({Image(3, 30)}))[0].end_utime, 4);
  EXPECT_THROW(PreparedViews(0), std::invalid_argument);
}

TEST(ViewPoolTest, GivesBackBuffersUpToItsCapacity) {
  ViewPool pool(2);
  EXPECT_TRUE(pool.Take().silhouette.mask.empty()) << "empty at first";
  std::vector<PreparedView> used(3);
  for (PreparedView& view : used) view.silhouette.mask.create(4, 4, CV_8U);
  const uchar* buffer = used[0].silhouette.mask.data;
  pool.Give(&used);
  EXPECT_TRUE(used.empty());
  const PreparedView second = pool.Take();
  const PreparedView first = pool.Take();
  EXPECT_EQ(first.silhouette.mask.data, buffer) << "the same buffer, not a copy";
  EXPECT_FALSE(second.silhouette.mask.empty());
  EXPECT_TRUE(pool.Take().silhouette.mask.empty()) << "the third went beyond the capacity";
}

}  // namespace
}  // namespace shapesense
