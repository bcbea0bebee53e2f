#include "core/progress.h"

#include <gtest/gtest.h>

#include <sstream>
#include <thread>
#include <vector>

namespace fvm {
namespace {

TEST(Progress, DisabledPrintsNothing) {
  std::ostringstream out;
  {
    Progress progress("pairs", 10, /*enabled=*/false, out);
    for (int i = 0; i < 10; ++i) progress.Advance();
    progress.Finish();
    EXPECT_EQ(progress.done(), 10);  // it still counts
  }
  EXPECT_EQ(out.str(), "");
}

TEST(Progress, EnabledEndsWithTheFinalCountOnItsOwnLine) {
  std::ostringstream out;
  Progress progress("tiles", 3, /*enabled=*/true, out);
  for (int i = 0; i < 3; ++i) progress.Advance();
  progress.Finish();
  progress.Finish();  // a second Finish draws nothing more
  const std::string text = out.str();
  // The first Advance draws at once; the two after it come within 100 ms and are throttled; Finish draws.
  EXPECT_EQ(text, "\rtiles: 1/3\rtiles: 3/3\n");
}

TEST(Progress, CountsEveryStepFromSeveralThreads) {
  std::ostringstream out;
  Progress progress("pairs", 4000, /*enabled=*/true, out);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 1000; ++i) progress.Advance();
    });
  }
  for (auto& t : threads) t.join();
  progress.Finish();
  EXPECT_EQ(progress.done(), 4000);
  const std::string text = out.str();
  const std::string last = "\rpairs: 4000/4000\n";
  ASSERT_GE(text.size(), last.size());
  EXPECT_EQ(text.substr(text.size() - last.size()), last);
}

TEST(Progress, UnwindingEndsTheLineSoAnErrorStartsOnAFreshOne) {
  std::ostringstream out;
  {
    Progress progress("slices", 5, /*enabled=*/true, out);
    progress.Advance(2);
  }
  EXPECT_EQ(out.str(), "\rslices: 2/5\n");
}

}  // namespace
}  // namespace fvm
