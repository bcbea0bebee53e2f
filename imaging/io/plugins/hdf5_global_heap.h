#pragma once
// HDF5's global heap collections checked from the file's bytes before HDF5 reads them. A collection ("GCOL", version
// 1, its size, then objects: index, references, reserved, size, data padded to 8 bytes; HDF5 File Format
// Specification 1.10, III.E) is walked as HDF5 1.10.8 walks it when it loads one (H5HG__cache_heap_deserialize):
// a free-space object (index 0) of size 0 keeps that walk in place for ever, and an object running past its
// collection sends it beyond its buffer. Both were found by the fuzzer in damaged DATX files; HDF5 does not check.

#include <string>

namespace fvm::imaging {

// Empty when every collection in `bytes` walks to its end; else what is wrong ("the global heap collection at byte
// 4512 ..."). Four bytes "GCOL" not followed by a version-1 header that fits the file are not taken for a collection.
std::string DamagedGlobalHeap(const std::string& bytes);

}  // namespace fvm::imaging
