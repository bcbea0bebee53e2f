#include "imaging/io/plugins/datx_metadata.h"

#include <cstdint>
#include <deque>
#include <cstring>
#include <string>
#include <vector>

#include "imaging/io/plugins/hdf5_support.h"

namespace fvm::imaging {
namespace {

using hdf5::Checked;
using hdf5::Handle;

// Mx's table has a few hundred rows; a table of more than 16 MB in memory is not one.
constexpr std::size_t kLargestTableBytes = std::size_t{16} << 20;

struct MetaDataRow {
  std::string source, link, destination;
};

// One string member of the table's compound, as the file stores it (variable or fixed length).
struct TextMember {
  const char* name;
  bool variable = false;
  std::size_t size = 0, offset = 0;
};

bool IsDataset(hid_t file, const std::string& path) {
  if (path.empty() || path[0] != '/' || path.size() > hdf5::kLongestText) return false;
  H5O_info_t info;
  return H5Lexists(file, path.c_str(), H5P_DEFAULT) > 0 &&
         H5Oget_info_by_name2(file, path.c_str(), &info, H5O_INFO_BASIC, H5P_DEFAULT) >= 0 &&
         info.type == H5O_TYPE_DATASET;
}

// The rows of /MetaData, or none when it is not a table of three strings.
std::vector<MetaDataRow> ReadTable(hid_t file) {
  if (H5Lexists(file, "/MetaData", H5P_DEFAULT) <= 0 || !IsDataset(file, "/MetaData")) return {};
  Handle table(H5Dopen2(file, "/MetaData", H5P_DEFAULT), H5Dclose);
  Handle type(table.ok() ? H5Dget_type(table.get()) : -1, H5Tclose);
  Handle space(table.ok() ? H5Dget_space(table.get()) : -1, H5Sclose);
  if (!type.ok() || !space.ok() || H5Tget_class(type.get()) != H5T_COMPOUND || !hdf5::MembersApart(type.get())) {
    return {};
  }
  const hssize_t rows = hdf5::Points(space.get());
  TextMember members[3] = {{"Source"}, {"Link"}, {"Destination"}};
  Handle memory(H5Tcreate(H5T_COMPOUND, 3 * hdf5::kLongestText + 64), H5Tclose);
  std::deque<Handle> member_types;  // a deque: Handle does not move
  std::size_t offset = 0;
  for (TextMember& m : members) {
    const int index = H5Tget_member_index(type.get(), m.name);
    if (index < 0) return {};
    Handle file_member(H5Tget_member_type(type.get(), static_cast<unsigned>(index)), H5Tclose);
    if (!file_member.ok() || H5Tget_class(file_member.get()) != H5T_STRING) return {};
    m.variable = H5Tis_variable_str(file_member.get()) > 0;
    m.size = m.variable ? sizeof(char*) : H5Tget_size(file_member.get());
    if (m.size == 0 || m.size > hdf5::kLongestText) return {};
    member_types.emplace_back(H5Tcopy(H5T_C_S1), H5Tclose);
    if (H5Tset_size(member_types.back().get(), m.variable ? H5T_VARIABLE : m.size) < 0) return {};
    m.offset = offset;
    if (H5Tinsert(memory.get(), m.name, offset, member_types.back().get()) < 0) return {};
    offset = (offset + m.size + 7) / 8 * 8;
  }
  if (rows < 1 || static_cast<std::uint64_t>(rows) > kLargestTableBytes / offset ||
      H5Tset_size(memory.get(), offset) < 0) {
    return {};
  }
  std::vector<unsigned char> buffer(offset * static_cast<std::size_t>(rows), 0);
  if (Checked(H5Dread(table.get(), memory.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data())) < 0) return {};
  std::vector<MetaDataRow> out(static_cast<std::size_t>(rows));
  for (std::size_t r = 0; r < out.size(); ++r) {
    std::string* fields[3] = {&out[r].source, &out[r].link, &out[r].destination};
    for (int k = 0; k < 3; ++k) {
      const unsigned char* p = buffer.data() + r * offset + members[k].offset;
      if (members[k].variable) {
        const char* s = nullptr;
        std::memcpy(&s, p, sizeof s);
        if (s) fields[k]->assign(s, strnlen(s, hdf5::kLongestText));
      } else {
        fields[k]->assign(reinterpret_cast<const char*>(p), strnlen(reinterpret_cast<const char*>(p), members[k].size));
      }
    }
  }
  H5Dvlen_reclaim(memory.get(), space.get(), H5P_DEFAULT, buffer.data());
  return out;
}

// The destination of the row (source, link), or empty.
std::string Follow(const std::vector<MetaDataRow>& table, const std::string& source, const std::string& link) {
  for (const MetaDataRow& row : table) {
    if (row.source == source && row.link == link) return row.destination;
  }
  return {};
}

}  // namespace

std::string DatxMetaDataPath(hid_t file, const std::string& channel) {
  const std::vector<MetaDataRow> table = ReadTable(file);
  const std::string measurement = Follow(table, "Root", "Measurement");
  const std::string node = measurement.empty() ? std::string() : Follow(table, measurement, channel);
  const std::string path = node.empty() ? std::string() : Follow(table, node, "Path");
  return IsDataset(file, path) ? path : std::string();
}

}  // namespace fvm::imaging
