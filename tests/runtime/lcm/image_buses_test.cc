// Each camera's images on a port of its own (runtime/lcm/image_buses.h).
#include "runtime/lcm/image_buses.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace shapesense {
namespace {

TEST(ImageUrlTest, EachCameraGetsThePortAfterTheRigsPlusItsIndex) {
  EXPECT_EQ(ImageUrl("udpm://239.255.76.67:7667?ttl=0", 0), "udpm://239.255.76.67:7668?ttl=0");
  EXPECT_EQ(ImageUrl("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304", 2),
            "udpm://239.255.76.67:7670?ttl=0&recv_buf_size=4194304");
  EXPECT_EQ(ImageUrl("udpm://239.255.76.68:9000", 1), "udpm://239.255.76.68:9002");
  // LCM's default port when the URL has none.
  EXPECT_EQ(ImageUrl("udpm://239.255.76.67", 0), "udpm://239.255.76.67:7668");
  EXPECT_EQ(ImageUrl("udpm://239.255.76.67?ttl=1", 0), "udpm://239.255.76.67:7668?ttl=1");
}

TEST(ImageUrlTest, OtherProvidersKeepTheImagesOnTheMainBus) {
  EXPECT_EQ(ImageUrl("memq://", 3), "memq://");
  EXPECT_EQ(ImageUrl("file:///tmp/x.lcmlog?mode=w", 1), "file:///tmp/x.lcmlog?mode=w");
  EXPECT_FALSE(HasImageBuses("memq://"));
  EXPECT_TRUE(HasImageBuses("udpm://239.255.76.67:7667"));
}

TEST(ImageUrlTest, ABadPortIsNamed) {
  try {
    ImageUrl("udpm://239.255.76.67:76x7", 0);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'76x7'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ImageUrl("udpm://239.255.76.67:65535", 0), std::invalid_argument);
  EXPECT_THROW(ImageUrl("udpm://239.255.76.67:", 0), std::invalid_argument);
}

TEST(ImageBusesTest, OnMemqEveryCameraIsTheMainBus) {
  LcmBus main("memq://");
  ImageBuses buses(main, 3);
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(&buses.ForCamera(k), &main);
  EXPECT_TRUE(buses.Opened().empty());
}

}  // namespace
}  // namespace shapesense
