#pragma once
// The table by which Mx names a DATX measurement's datasets: /MetaData, rows of three strings (Source, Link,
// Destination), read as Pastewka's SurfaceTopography (2021, DATXReader) reads it: from "Root" the link
// "Measurement" leads to a node ("{...}"), from it "Surface" (or "Intensity") to another, and from that "Path" to the
// dataset ("/Data/Surface/{...}"). Where /Data/Surface holds several datasets (a measurement saved again after
// processing), this says which is the measurement's; the first by name is only the fallback.

#include <hdf5.h>

#include <string>

namespace fvm::imaging {

// The dataset path /MetaData gives for `channel` ("Surface", "Intensity"), or empty when the file has no such table,
// the chain is broken, or the path is not a dataset of the file. hdf5::out_of_memory is set when HDF5 ran out of
// memory reading the table.
std::string DatxMetaDataPath(hid_t file, const std::string& channel);

}  // namespace fvm::imaging
