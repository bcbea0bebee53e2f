// The pool of float maps behind focus variation's filters (imaging/focus_map_pool.h): a map's memory goes back to
// the pool only when no header refers to it any more, and is then handed out again instead of fresh pages.
#include "imaging/focus_map_pool.h"

#include <gtest/gtest.h>

namespace fvm {
namespace {

TEST(FocusMapPool, ReusesAMapsMemoryOnlyOnceNoHeaderHoldsIt) {
  imaging::MapPool pool(64, 48, false);
  cv::Mat a = pool.Map(), b = pool.Map();
  ASSERT_EQ(a.rows, 48);
  ASSERT_EQ(a.cols, 64);
  ASSERT_EQ(a.type(), CV_32F);
  ASSERT_TRUE(a.isContinuous());
  EXPECT_NE(a.data, b.data);
  const uchar* const a_memory = a.data;
  a.setTo(1.0f);
  cv::Mat rows = a.rowRange(10, 20);  // a stripe's header keeps the map alive after its own name lets go
  a.release();
  cv::Mat c = pool.Map();
  EXPECT_NE(c.data, a_memory);
  c.setTo(2.0f);
  EXPECT_EQ(rows.at<float>(0, 0), 1.0f);
  rows.release();
  const cv::Mat d = pool.Map();
  EXPECT_EQ(d.data, a_memory);  // the pages already in, not fresh ones
}

TEST(FocusMapPool, AMapReturnedFromAFunctionKeepsItsValuesWhileOthersAreTaken) {
  imaging::MapPool pool(32, 32, true);
  const auto filled = [&pool](float value) {
    cv::Mat scratch = pool.Map(), out = pool.Map();
    pool.Pass([&](int r0, int r1) { scratch.rowRange(r0, r1).setTo(value); });
    scratch.copyTo(out);
    return out;
  };
  const cv::Mat one = filled(1.0f), two = filled(2.0f);
  EXPECT_NE(one.data, two.data);
  EXPECT_EQ(cv::countNonZero(one != 1.0f), 0);
  EXPECT_EQ(cv::countNonZero(two != 2.0f), 0);
}

}  // namespace
}  // namespace fvm
