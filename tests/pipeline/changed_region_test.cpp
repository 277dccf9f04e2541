// bench settle --changed-region: the pixels an edit changes, from the references before and after.
#include <gtest/gtest.h>

#include <stdexcept>

#include "tools/afterglow/convergence.h"

namespace ag::cli {
namespace {

Image filled(int w, int h, float v) {
    Image image(w, h);
    for (float& p : image.pixels) p = v;
    return image;
}

TEST(ChangedRegion, KeepsThePixelsThatChangeByMoreThanTheFraction) {
    Image before = filled(8, 4, 1.0f);
    Image after = before;
    after.set_rgb(1, 1, glm::vec3(1.2f));   // brighter by 1/6 of the larger: in
    after.set_rgb(2, 1, glm::vec3(0.8f));   // darker by 20%: in
    after.set_rgb(3, 1, glm::vec3(1.05f));  // by 5%: out
    // Black before, lit after: in. Both nearly black (under 1% of the mean): out, however
    // large the relative change.
    before.set_rgb(4, 2, glm::vec3(0.0f));
    before.set_rgb(5, 2, glm::vec3(0.001f));
    after.set_rgb(5, 2, glm::vec3(0.004f));
    const Image mask = changed_region(before, after, 0.1);
    ASSERT_EQ(mask.width, 8);
    ASSERT_EQ(mask.height, 4);
    int in = 0;
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) in += mask.at(x, y)[0] != 0.0f;
    EXPECT_EQ(in, 3);
    EXPECT_NE(mask.at(1, 1)[0], 0.0f);
    EXPECT_NE(mask.at(2, 1)[0], 0.0f);
    EXPECT_EQ(mask.at(3, 1)[0], 0.0f);
    EXPECT_NE(mask.at(4, 2)[0], 0.0f);
    EXPECT_EQ(mask.at(5, 2)[0], 0.0f);
    // A smaller fraction takes the 5% pixel in too.
    const Image wider = changed_region(before, after, 0.04);
    EXPECT_NE(wider.at(3, 1)[0], 0.0f);
}

TEST(ChangedRegion, RefusesImagesOfDifferentSizes) {
    EXPECT_THROW(changed_region(filled(4, 4, 1.0f), filled(4, 5, 1.0f), 0.1),
                 std::invalid_argument);
}

}  // namespace
}  // namespace ag::cli
