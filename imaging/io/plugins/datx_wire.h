#pragma once
// DatxContent as bytes, for the pipe between the DATX plugin's HDF5 child process and fvm (hdf5_datx_codec.cc):
// a leading 1 (an answer; 0 starts an error text), then every field in order, a length before each string, list
// and map. Both ends are the same build, so numbers travel in the machine's byte order.

#include <cstdint>
#include <cstring>
#include <string>

#include "imaging/io/datx_codec.h"

namespace fvm::imaging {
namespace datx_wire {

// `Out` is anything with append(const char*, std::size_t): a std::string, or the HDF5 child's pipe, which then
// receives the values straight from their vectors (no second copy of a large map in the child).
template <typename Out>
void Put(Out& out, std::uint64_t n) {
  out.append(reinterpret_cast<const char*>(&n), sizeof n);
}
template <typename Out>
void Put(Out& out, const std::string& text) {
  Put(out, static_cast<std::uint64_t>(text.size()));
  out.append(text.data(), text.size());
}
template <typename Out>
void Put(Out& out, const std::vector<double>& values) {
  Put(out, static_cast<std::uint64_t>(values.size()));
  if (!values.empty()) out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double));
}
template <typename Out>
void Put(Out& out, const DatxDataset& d) {
  Put(out, d.path);
  Put(out, d.rows);
  Put(out, d.cols);
  Put(out, d.type_name);
  Put(out, d.values);
  Put(out, static_cast<std::uint64_t>(d.numbers.size()));
  for (const auto& [name, values] : d.numbers) Put(out, name), Put(out, values);
  Put(out, static_cast<std::uint64_t>(d.texts.size()));
  for (const auto& [name, text] : d.texts) Put(out, name), Put(out, text);
  Put(out, static_cast<std::uint64_t>(d.converters.size()));
  for (const auto& [name, c] : d.converters) Put(out, name), Put(out, c.category), Put(out, c.base_unit), Put(out, c.parameters);
}

class Reader {
 public:
  explicit Reader(const std::string& in) : in_(in) {}
  bool Get(std::uint64_t& n) {
    if (in_.size() - at_ < sizeof n) return false;
    std::memcpy(&n, in_.data() + at_, sizeof n);
    at_ += sizeof n;
    return true;
  }
  bool Get(std::string& text) {
    std::uint64_t n = 0;
    if (!Get(n) || in_.size() - at_ < n) return false;
    text.assign(in_, at_, n);
    at_ += n;
    return true;
  }
  bool Get(std::vector<double>& values) {
    std::uint64_t n = 0;
    if (!Get(n) || (in_.size() - at_) / sizeof(double) < n) return false;
    values.resize(n);
    if (n > 0) std::memcpy(values.data(), in_.data() + at_, n * sizeof(double));  // an empty vector's data() may be null
    at_ += n * sizeof(double);
    return true;
  }
  bool Get(DatxDataset& d) {
    std::uint64_t count = 0;
    if (!Get(d.path) || !Get(d.rows) || !Get(d.cols) || !Get(d.type_name) || !Get(d.values) || !Get(count)) {
      return false;
    }
    for (std::uint64_t i = 0; i < count; ++i) {
      std::string name;
      if (!Get(name) || !Get(d.numbers[name])) return false;
    }
    if (!Get(count)) return false;
    for (std::uint64_t i = 0; i < count; ++i) {
      std::string name;
      if (!Get(name) || !Get(d.texts[name])) return false;
    }
    if (!Get(count)) return false;
    for (std::uint64_t i = 0; i < count; ++i) {
      std::string name;
      if (!Get(name)) return false;
      DatxConverter& c = d.converters[name];
      if (!Get(c.category) || !Get(c.base_unit) || !Get(c.parameters)) return false;
    }
    return true;
  }
  bool AtEnd() const { return at_ == in_.size(); }

 private:
  const std::string& in_;
  std::size_t at_ = 0;
};

}  // namespace datx_wire

template <typename Out>
void EncodeDatx(const DatxContent& content, Out& out) {
  out.append("\1", 1);
  datx_wire::Put(out, content.surface);
  datx_wire::Put(out, static_cast<std::uint64_t>(content.intensity ? 1 : 0));
  if (content.intensity) datx_wire::Put(out, *content.intensity);
}

inline std::string EncodeDatx(const DatxContent& content) {
  std::string out;
  EncodeDatx(content, out);
  return out;
}

inline bool DecodeDatx(const std::string& in, DatxContent* content) {
  if (in.empty() || in[0] != '\1') return false;
  const std::string body = in.substr(1);
  datx_wire::Reader r(body);
  std::uint64_t has_intensity = 0;
  if (!r.Get(content->surface) || !r.Get(has_intensity)) return false;
  if (has_intensity) {
    content->intensity.emplace();
    if (!r.Get(*content->intensity)) return false;
  }
  return r.AtEnd();
}

}  // namespace fvm::imaging
