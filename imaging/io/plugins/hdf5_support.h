#pragma once
// What the DATX plugin's HDF5 code shares (hdf5_datx_codec.cc, datx_metadata.cc): identifiers closed on scope exit,
// the record of an allocation HDF5 could not make (under the child's memory cap), and the checks made before HDF5
// is trusted with a compound type from the file. Built into libfvm_datx_hdf5.so only.

#include <hdf5.h>

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace fvm::imaging::hdf5 {

// Strings beyond this length are not what DATX stores; they are cut there.
inline constexpr std::size_t kLongestText = 4096;

// Closes an HDF5 identifier when it goes out of scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// The number of elements of a dataspace, or -1 when it is not simple.
inline hssize_t Points(hid_t space) { return H5Sis_simple(space) > 0 ? H5Sget_simple_extent_npoints(space) : -1; }

// Set when an HDF5 call failed for want of memory (the child's cap, or the machine's).
inline bool out_of_memory = false;

inline herr_t NoteAllocationFailure(unsigned, const H5E_error2_t* error, void*) {
  if (error->min_num == H5E_NOSPACE || error->min_num == H5E_CANTALLOC) out_of_memory = true;
  return 0;
}

// Records whether HDF5's call failed allocating memory; to be wrapped around the failing call itself, before the
// next HDF5 call clears its error stack.
inline herr_t Checked(herr_t status) {
  if (status < 0) H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, NoteAllocationFailure, nullptr);
  return status;
}

// True when the compound's members lie inside it, none over another. HDF5 1.10.8 does not check: one damaged member
// offset (found by the fuzzer) made it take part of the converter's Parameters for BaseUnit's string length and
// allocate 2.3 GB for it.
inline bool MembersApart(hid_t compound) {
  const int count = H5Tget_nmembers(compound);
  const std::size_t size = H5Tget_size(compound);
  if (count < 1 || count > 64 || size == 0) return false;
  std::vector<std::pair<std::size_t, std::size_t>> spans;  // [begin, end) of each member
  for (int i = 0; i < count; ++i) {
    Handle member(H5Tget_member_type(compound, static_cast<unsigned>(i)), H5Tclose);
    const std::size_t member_size = member.ok() ? H5Tget_size(member.get()) : 0;
    const std::size_t offset = H5Tget_member_offset(compound, static_cast<unsigned>(i));
    if (member_size == 0 || offset > size || member_size > size - offset) return false;
    spans.emplace_back(offset, offset + member_size);
  }
  std::sort(spans.begin(), spans.end());
  for (std::size_t i = 1; i < spans.size(); ++i) {
    if (spans[i].first < spans[i - 1].second) return false;
  }
  return true;
}

}  // namespace fvm::imaging::hdf5
