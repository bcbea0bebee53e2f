#include "imaging/focus_map_pool.h"

#include <cstddef>
#include <utility>

namespace fvm::imaging {

cv::Mat MapPool::Map() {
  cv::Mat map;
  map.allocator = this;
  map.create(height_, width_, CV_32F);
  return map;
}

// As OpenCV's own allocator for host memory (StdMatAllocator, modules/core/src/matrix.cpp), with the memory from
// the pool.
cv::UMatData* MapPool::allocate(int dims, const int* sizes, int type, void* data, size_t* step, cv::AccessFlag,
                                cv::UMatUsageFlags) const {
  std::size_t total = CV_ELEM_SIZE(type);
  for (int i = dims - 1; i >= 0; --i) {
    if (step) {
      if (data && step[i] != cv::Mat::AUTO_STEP) {
        CV_Assert(total <= step[i]);
        total = step[i];
      } else {
        step[i] = total;
      }
    }
    total *= std::size_t(sizes[i]);
  }
  auto* u = new cv::UMatData(this);
  u->size = total;
  if (data) {
    u->data = u->origdata = static_cast<uchar*>(data);
    u->flags |= cv::UMatData::USER_ALLOCATED;
    return u;
  }
  const std::size_t floats = (total + sizeof(float) - 1) / sizeof(float);
  std::unique_ptr<HugeVector<float>> memory;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = free_.rbegin(); it != free_.rend(); ++it) {
      if ((*it)->size() == floats) {
        memory = std::move(*it);
        free_.erase(std::next(it).base());
        break;
      }
    }
  }
  if (!memory) {
    memory = std::make_unique<HugeVector<float>>();
    memory->resize(floats);  // uninitialised (HugePageAllocator): not touched here
  }
  u->data = u->origdata = reinterpret_cast<uchar*>(memory->data());
  u->handle = memory.release();
  return u;
}

bool MapPool::allocate(cv::UMatData* data, cv::AccessFlag, cv::UMatUsageFlags) const { return data != nullptr; }

void MapPool::deallocate(cv::UMatData* u) const {
  if (!u) return;
  CV_Assert(u->urefcount == 0 && u->refcount == 0);
  if (!(u->flags & cv::UMatData::USER_ALLOCATED)) {
    std::unique_ptr<HugeVector<float>> memory(static_cast<HugeVector<float>*>(u->handle));
    const std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(memory));
  }
  delete u;
}

}  // namespace fvm::imaging
