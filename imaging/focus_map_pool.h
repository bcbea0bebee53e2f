#pragma once
// The float maps focus variation's filters fill (focus_height_maps.h, focus_variation.cc), of the height map's size,
// over memory in huge pages reused from map to map: fresh 4 kB pages cost more than the filters that fill them (a
// page fault per 4 kB on a virtual machine). Each map is an ordinary cv::Mat, named where it is taken: a map that
// outlives the function filling it is returned (or held by a struct of named maps), a scratch map is a local. The pool
// is the maps' allocator (cv::MatAllocator), so OpenCV's own reference count says when no header refers to a map any
// more; its memory then goes back to the pool for the next map taken. So no function can clobber a map another
// still holds, and the pool holds as many maps' memory as were ever alive at once. The pool outlives its maps
// (declare it before them). Internal to imaging/ (OpenCV types).
//
// The maps are filled and filtered in stripes of rows in parallel (Pass): a filter applied to a stripe of a map
// reads the rows beyond it from the map itself (OpenCV filters a sub-matrix with its real neighbours unless told
// BORDER_ISOLATED), so each stripe's result is that of the whole map's filter.

#include <opencv2/core.hpp>

#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "imaging/focus_stack_curves.h"

namespace fvm::imaging {

class MapPool final : public cv::MatAllocator {
 public:
  MapPool(int width, int height, bool parallel) : width_(width), height_(height), parallel_(parallel) {}
  MapPool(const MapPool&) = delete;
  MapPool& operator=(const MapPool&) = delete;

  // A height x width float map, left uninitialised: each pass writes all of it, and the first write faults fresh
  // pages in where it happens (in the pass's parallel stripes), not in one thread's fill.
  cv::Mat Map();
  // body(r0, r1) for each stripe of rows; every stripe of a pass ends before the next pass starts.
  void Pass(const std::function<void(int, int)>& body, int stripe_rows = kStripeRows) const {
    ForStripes(height_, parallel_, body, stripe_rows);
  }
  int width() const { return width_; }
  int height() const { return height_; }
  bool parallel() const { return parallel_; }

  // cv::MatAllocator: a map's memory from the pool's free memory (or fresh) and back to it.
  cv::UMatData* allocate(int dims, const int* sizes, int type, void* data, size_t* step, cv::AccessFlag flags,
                         cv::UMatUsageFlags usage) const override;
  bool allocate(cv::UMatData* data, cv::AccessFlag flags, cv::UMatUsageFlags usage) const override;
  void deallocate(cv::UMatData* data) const override;

 private:
  int width_, height_;
  bool parallel_;
  // Memory no map holds, in the order it was freed; the last freed is taken first (its pages are in, and likely in
  // cache). Guarded by `mutex_`: a stripe's header may be the last to let go of a map.
  mutable std::mutex mutex_;
  mutable std::vector<std::unique_ptr<HugeVector<float>>> free_;
};

}  // namespace fvm::imaging
