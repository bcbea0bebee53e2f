// The Zygo DATX codec on HDF5's C library, built as the plugin libfvm_datx_hdf5.so (see imaging/io/datx_codec.h).
// The file is opened from memory (HDF5's core driver over the bytes fvm read), every dataset and attribute is
// checked for its class, rank and size before anything is allocated, and every failure comes back as text. HDF5's
// own error printing is turned off: fvm says what was wrong.
//
// HDF5 1.10 is not safe on damaged files: three changed header bytes made it read through wild pointers (in
// H5Aopen_by_idx, in its global heap under H5Aread). So the reading runs in a child process (fork), which sends
// what it read back through a pipe (datx_wire.h): a damaged file that crashes or hangs HDF5 kills the child, and
// fvm refuses the file instead of crashing. HDF5 (Debian's serial build) is not thread-safe either: one read at a
// time. The child's address space is capped (RLIMIT_AS, MemoryCap below): one changed byte in a 12 KB file made HDF5
// allocate and fill 2.3 GB for a string attribute; under the cap the allocation fails at once and the file is
// refused with the cap named.

#include <hdf5.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "imaging/io/datx_codec.h"
#include "imaging/io/plugins/datx_metadata.h"
#include "imaging/io/plugins/datx_wire.h"
#include "imaging/io/plugins/hdf5_global_heap.h"
#include "imaging/io/plugins/hdf5_support.h"

namespace fvm::imaging {
namespace {

using hdf5::Checked;
using hdf5::Handle;
using hdf5::MembersApart;
using hdf5::Points;

// Attributes beyond these sizes are not what DATX stores; they are skipped, never read.
constexpr hssize_t kLargestAttribute = 64;
using hdf5::kLongestText;

// The HDF5 child's address space, capped with RLIMIT_AS and raised as the read goes, so that a damaged header cannot
// make HDF5 allocate what no DATX of this size needs. HDF5's work on a DATX's metadata (attributes of at most 64
// values and strings of at most 4 KB, its metadata cache, the file's image copied into its core driver) stays within
// kHdf5WorkingBytes and four times the file; a dataset's values, once its grid is known and checked against the
// largest grid fvm accepts for a file of this size (max_points, zygo_datx.cc), add 24 bytes a value: the value as a
// double and twice as much for HDF5's chunk, conversion and decompression buffers (the answer is written to the pipe
// from the values themselves, PipeOut, with no copy).
class MemoryCap {
 public:
  static constexpr std::uint64_t kHdf5WorkingBytes = std::uint64_t{64} << 20;
  static constexpr std::uint64_t kBytesPerValue = 24;

  explicit MemoryCap(std::size_t file_bytes) : base_(kHdf5WorkingBytes + 4 * std::uint64_t{file_bytes}) { Allow(0); }

  // Caps the address space at what is mapped now, the base allowance and `extra` bytes.
  void Allow(std::uint64_t extra) {
    allowance_ = base_ + extra;
    rlimit limit{};
    const std::uint64_t mapped = MappedBytes();
    if (mapped == 0 || getrlimit(RLIMIT_AS, &limit) != 0) return;  // without /proc, no cap rather than a wrong one
    const std::uint64_t wanted = mapped + allowance_;
    limit.rlim_cur = limit.rlim_max == RLIM_INFINITY ? wanted : std::min<std::uint64_t>(wanted, limit.rlim_max);
    setrlimit(RLIMIT_AS, &limit);
  }

  // "the N MB the reader allows beyond what fvm had mapped (RLIMIT_AS)", for the refusal.
  std::string Describe() const {
    return std::to_string((allowance_ + (1u << 20) - 1) >> 20) +
           " MB that fvm's HDF5 reader may map for a file of this size and grid (its cap, RLIMIT_AS)";
  }

 private:
  // The bytes the process maps now: the first field of /proc/self/statm, in pages.
  static std::uint64_t MappedBytes() {
    char text[64] = {};
    const int fd = open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
    if (fd < 0) return 0;
    const ssize_t n = read(fd, text, sizeof text - 1);
    close(fd);
    if (n <= 0) return 0;
    return std::strtoull(text, nullptr, 10) * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
  }

  std::uint64_t base_;
  std::uint64_t allowance_ = 0;
};

// The first string of a string attribute (fixed or variable length).
bool ReadText(hid_t attribute, hid_t type, hid_t space, std::string* text) {
  const hssize_t n = Points(space);
  if (n < 1 || n > kLargestAttribute) return false;
  Handle memory(H5Tcopy(H5T_C_S1), H5Tclose);
  if (H5Tis_variable_str(type) > 0) {
    if (H5Tset_size(memory.get(), H5T_VARIABLE) < 0) return false;
    std::vector<char*> strings(static_cast<std::size_t>(n), nullptr);
    if (Checked(H5Aread(attribute, memory.get(), strings.data())) < 0) return false;
    if (strings[0]) *text = std::string(strings[0], strnlen(strings[0], kLongestText));
    H5Dvlen_reclaim(memory.get(), space, H5P_DEFAULT, strings.data());
    return true;
  }
  const std::size_t size = H5Tget_size(type);
  if (size == 0 || size > kLongestText || H5Tset_size(memory.get(), size) < 0) return false;
  std::vector<char> buffer(size * static_cast<std::size_t>(n));
  if (Checked(H5Aread(attribute, memory.get(), buffer.data())) < 0) return false;
  *text = std::string(buffer.data(), strnlen(buffer.data(), size));
  return true;
}

// A converter: the compound's Category and BaseUnit strings and its Parameters (variable-length doubles), each
// read only when the file's compound has it in a form read here.
bool ReadConverter(hid_t attribute, hid_t type, hid_t space, DatxConverter* converter) {
  const hssize_t n = Points(space);
  if (n < 1 || n > kLargestAttribute || !MembersApart(type)) return false;
  struct Member {
    const char* name;
    bool variable = false;
    std::size_t size = 0, offset = 0;
    bool present = false;
    hsize_t array_count = 0;  // Parameters as a fixed array of numbers, not a variable-length list
  };
  Member members[3] = {{"Category"}, {"BaseUnit"}, {"Parameters"}};
  Handle memory(H5Tcreate(H5T_COMPOUND, 2048), H5Tclose);  // 2 strings of 256 bytes and 64 doubles at most
  std::size_t offset = 0;
  std::vector<hid_t> member_types;
  for (Member& m : members) {
    const int index = H5Tget_member_index(type, m.name);
    if (index < 0) continue;
    const hid_t file_member = H5Tget_member_type(type, static_cast<unsigned>(index));
    if (file_member < 0) continue;
    const H5T_class_t member_class = H5Tget_class(file_member);
    hid_t memory_member = -1;
    if (member_class == H5T_STRING) {
      memory_member = H5Tcopy(H5T_C_S1);
      m.variable = H5Tis_variable_str(file_member) > 0;
      m.size = m.variable ? sizeof(char*) : H5Tget_size(file_member);
      if (m.size == 0 || m.size > 256 || H5Tset_size(memory_member, m.variable ? H5T_VARIABLE : m.size) < 0) {
        H5Tclose(memory_member);
        memory_member = -1;
      }
    } else if (member_class == H5T_VLEN && std::strcmp(m.name, "Parameters") == 0) {
      memory_member = H5Tvlen_create(H5T_NATIVE_DOUBLE);
      m.size = sizeof(hvl_t);
    } else if (member_class == H5T_ARRAY && std::strcmp(m.name, "Parameters") == 0 &&
               H5Tget_array_ndims(file_member) == 1 && H5Tget_array_dims2(file_member, &m.array_count) == 1 &&
               m.array_count >= 1 && m.array_count <= static_cast<hsize_t>(kLargestAttribute)) {
      // The same numbers as a fixed-length array (h5py writes a list of equal lengths so).
      memory_member = H5Tarray_create2(H5T_NATIVE_DOUBLE, 1, &m.array_count);
      m.size = static_cast<std::size_t>(m.array_count) * sizeof(double);
    }
    H5Tclose(file_member);
    if (memory_member < 0) continue;
    offset = (offset + 7) / 8 * 8;
    m.offset = offset;
    m.present = H5Tinsert(memory.get(), m.name, offset, memory_member) >= 0;
    offset += m.size;
    member_types.push_back(memory_member);
  }
  bool read = false;
  if (offset > 0 && H5Tset_size(memory.get(), (offset + 7) / 8 * 8) >= 0) {
    const std::size_t record = (offset + 7) / 8 * 8;
    std::vector<unsigned char> buffer(record * static_cast<std::size_t>(n), 0);
    if (Checked(H5Aread(attribute, memory.get(), buffer.data())) >= 0) {
      read = true;
      for (const Member& m : members) {
        if (!m.present) continue;
        const unsigned char* p = buffer.data() + m.offset;
        if (m.array_count > 0) {
          converter->parameters.resize(static_cast<std::size_t>(m.array_count));
          std::memcpy(converter->parameters.data(), p, m.size);
          continue;
        }
        if (std::strcmp(m.name, "Parameters") == 0) {
          hvl_t vl;
          std::memcpy(&vl, p, sizeof vl);
          const double* values = static_cast<const double*>(vl.p);
          if (values && vl.len <= static_cast<std::size_t>(kLargestAttribute)) {
            converter->parameters.assign(values, values + vl.len);
          }
          continue;
        }
        std::string text;
        if (m.variable) {
          const char* s = nullptr;
          std::memcpy(&s, p, sizeof s);
          if (s) text.assign(s, strnlen(s, kLongestText));
        } else {
          text.assign(reinterpret_cast<const char*>(p), strnlen(reinterpret_cast<const char*>(p), m.size));
        }
        (std::strcmp(m.name, "Category") == 0 ? converter->category : converter->base_unit) = text;
      }
      H5Dvlen_reclaim(memory.get(), space, H5P_DEFAULT, buffer.data());
    }
  }
  for (const hid_t t : member_types) H5Tclose(t);
  return read;
}

// The attributes DATX gives a surface, each read when present in a form read here: numbers, strings, converters.
// They are opened by name: HDF5 1.10's walk over all attributes by index crashed on damaged attribute tables. One that
// cannot be read is left out (zygo_datx.cc says which it needed), unless HDF5 ran out of memory reading it: false then,
// with the attribute named.
bool ReadAttributes(hid_t dataset, DatxDataset* out, std::string* error) {
  static constexpr const char* kNames[] = {"Unit",       "No Data",          "X Converter",
                                           "Y Converter", "Z Converter",     "Wavelength",
                                           "Interferometric Scale Factor",   "Obliquity Factor"};
  for (const char* name : kNames) {
    if (H5Aexists(dataset, name) <= 0) continue;
    Handle attribute(H5Aopen(dataset, name, H5P_DEFAULT), H5Aclose);
    if (!attribute.ok()) continue;
    Handle type(H5Aget_type(attribute.get()), H5Tclose);
    Handle space(H5Aget_space(attribute.get()), H5Sclose);
    if (!type.ok() || !space.ok()) continue;
    const H5T_class_t type_class = H5Tget_class(type.get());
    if (type_class == H5T_INTEGER || type_class == H5T_FLOAT) {
      const hssize_t n = Points(space.get());
      if (n < 1 || n > kLargestAttribute) continue;
      std::vector<double> values(static_cast<std::size_t>(n));
      if (Checked(H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, values.data())) >= 0) {
        out->numbers[name] = std::move(values);
      }
    } else if (type_class == H5T_STRING) {
      std::string text;
      if (ReadText(attribute.get(), type.get(), space.get(), &text)) out->texts[name] = std::move(text);
    } else if (type_class == H5T_COMPOUND) {
      DatxConverter converter;
      if (ReadConverter(attribute.get(), type.get(), space.get(), &converter)) out->converters[name] = converter;
    }
    if (hdf5::out_of_memory) {
      *error = out->path + " attribute '" + name + "'";
      return false;
    }
  }
  return true;
}

std::string TypeName(hid_t type) {
  const H5T_class_t type_class = H5Tget_class(type);
  const std::size_t bits = 8 * H5Tget_size(type);
  if (type_class == H5T_FLOAT) return "float" + std::to_string(bits);
  if (type_class == H5T_INTEGER) return (H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits);
  return "not a number";
}

// The dataset at `path`, two-dimensional and numeric, of at most `max_points` values. When HDF5 runs out of memory,
// `error` names what it was reading and hdf5::out_of_memory is set.
bool ReadDataset(hid_t file, const std::string& path, std::uint64_t max_points, MemoryCap& cap, DatxDataset* out,
                 std::string* error) {
  Handle dataset(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!dataset.ok()) {
    *error = path + " cannot be opened as a dataset";
    return false;
  }
  out->path = path;
  Handle type(H5Dget_type(dataset.get()), H5Tclose);
  Handle space(H5Dget_space(dataset.get()), H5Sclose);
  if (!type.ok() || !space.ok()) {
    *error = path + " has an unreadable type or shape";
    return false;
  }
  out->type_name = TypeName(type.get());
  const H5T_class_t type_class = H5Tget_class(type.get());
  if (type_class != H5T_INTEGER && type_class != H5T_FLOAT) {
    *error = path + " holds " + out->type_name + ", not numbers";
    return false;
  }
  hsize_t dims[2] = {0, 0};
  if (H5Sis_simple(space.get()) <= 0 || H5Sget_simple_extent_ndims(space.get()) != 2 ||
      H5Sget_simple_extent_dims(space.get(), dims, nullptr) != 2) {
    *error = path + " is not a two-dimensional dataset";
    return false;
  }
  out->rows = dims[0];
  out->cols = dims[1];
  if (dims[0] == 0 || dims[1] == 0 || dims[0] > max_points || dims[1] > max_points / dims[0]) {
    *error = path + " says " + std::to_string(dims[1]) + " x " + std::to_string(dims[0]) +
             " points, more than fvm reads from a file of this size (" + std::to_string(max_points) + ")";
    return false;
  }
  if (!ReadAttributes(dataset.get(), out, error)) return false;
  cap.Allow(MemoryCap::kBytesPerValue * dims[0] * dims[1]);
  out->values.resize(static_cast<std::size_t>(dims[0] * dims[1]));
  if (Checked(H5Dread(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out->values.data())) < 0) {
    *error = path + (hdf5::out_of_memory ? " values" : ": its " + std::to_string(dims[1]) + " x " +
                                                         std::to_string(dims[0]) + " values cannot be read");
    out->values.clear();
    return false;
  }
  return true;
}

bool IsGroup(hid_t file, const char* path) {
  H5O_info_t info;
  return H5Lexists(file, path, H5P_DEFAULT) > 0 && H5Oget_info_by_name2(file, path, &info, H5O_INFO_BASIC,
                                                                         H5P_DEFAULT) >= 0 && info.type == H5O_TYPE_GROUP;
}

// Where the channel `what` ("Surface", "Intensity") is: the dataset /MetaData names (datx_metadata.h), else the first
// link of /Data/<what> by name, else /Measurement/<what>; empty when there is none.
std::string ChannelPath(hid_t file, const std::string& what) {
  if (std::string named = DatxMetaDataPath(file, what); !named.empty()) return named;
  const std::string group = "/Data/" + what;
  if (IsGroup(file, "/Data") && IsGroup(file, group.c_str())) {
    char name[512] = {};
    if (H5Lget_name_by_idx(file, group.c_str(), H5_INDEX_NAME, H5_ITER_INC, 0, name, sizeof name, H5P_DEFAULT) > 0 &&
        std::strlen(name) < sizeof name - 1) {
      return group + "/" + name;
    }
  }
  const std::string nx2 = "/Measurement/" + what;
  if (IsGroup(file, "/Measurement") && H5Lexists(file, nx2.c_str(), H5P_DEFAULT) > 0) return nx2;
  return {};
}

bool ReadHere(const std::string& bytes, std::uint64_t max_points, MemoryCap& cap, DatxContent* content,
              std::string* error) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (!access.ok() || H5Pset_fapl_core(access.get(), 1 << 16, 0) < 0 ||
      H5Pset_file_image(access.get(), const_cast<char*>(bytes.data()), bytes.size()) < 0) {
    *error = "HDF5 could not take the file's bytes";
    return false;
  }
  Handle file(H5Fopen("datx", H5F_ACC_RDONLY, access.get()), H5Fclose);
  if (!file.ok()) {
    *error = "HDF5 cannot open it (a damaged HDF5 file)";
    return false;
  }
  const std::string surface = ChannelPath(file.get(), "Surface");
  if (hdf5::out_of_memory) {
    *error = "/MetaData";
    return false;
  }
  if (surface.empty()) {
    *error = "has neither a /Data/Surface group nor a /Measurement/Surface dataset: an HDF5 file, not a Zygo DATX";
    return false;
  }
  if (!ReadDataset(file.get(), surface, max_points, cap, &content->surface, error)) return false;
  const std::string intensity = ChannelPath(file.get(), "Intensity");
  if (hdf5::out_of_memory) {
    *error = "/MetaData";
    return false;
  }
  if (!intensity.empty()) {
    // An intensity that cannot be read is left out; one that exhausts the memory cap refuses the file.
    DatxDataset image;
    std::string failure;
    if (ReadDataset(file.get(), intensity, max_points, cap, &image, &failure)) {
      content->intensity = std::move(image);
    } else if (hdf5::out_of_memory) {
      *error = failure;
      return false;
    }
  }
  return true;
}

// The write end of the child's pipe as EncodeDatx's output: each piece is written as it comes.
class PipeOut {
 public:
  explicit PipeOut(int fd) : fd_(fd) {}
  void append(const char* data, std::size_t size) {
    for (std::size_t sent = 0; ok_ && sent < size;) {
      const ssize_t n = write(fd_, data + sent, size - sent);
      ok_ = n > 0;
      sent += ok_ ? static_cast<std::size_t>(n) : 0;
    }
  }
  void Refuse(const std::string& why) {
    append("\0", 1);
    append(why.data(), why.size());
  }
  bool ok() const { return ok_; }

 private:
  int fd_;
  bool ok_ = true;
};

// The child's work: sends EncodeDatx of what it read, or a 0 byte and the refusal. Running out of memory under the
// cap (HDF5's allocations failing, or fvm's own) is a refusal that names the cap. False when the pipe broke.
bool AnswerFromChild(const std::string& bytes, std::uint64_t max_points, int fd) {
  PipeOut out(fd);
  MemoryCap cap(bytes.size());
  std::string what = "its values";
  try {
    DatxContent read;
    if (ReadHere(bytes, max_points, cap, &read, &what)) {
      EncodeDatx(read, out);
      return out.ok();
    }
    if (!hdf5::out_of_memory) {
      out.Refuse(what);
      return out.ok();
    }
  } catch (const std::bad_alloc&) {
  }
  out.Refuse("HDF5 ran out of memory reading " + what + ": it needed more than the " + cap.Describe() +
             ", which no intact DATX of this size needs");
  return out.ok();
}

// HDF5 caught in a loop by a damaged file spins on the processor: the child may use 0.5 s of processor time and
// 0.25 s more per MB of file (a 25 MB DATX of 4 M points reads in 0.3 s), then SIGPROF ends it. Processor time,
// not the clock's, so that a loaded machine does not refuse a good file.
int ProcessorMs(std::size_t file_bytes) {
  return 500 + static_cast<int>(std::min<std::size_t>(file_bytes >> 20, 1u << 20) * 250);
}

void LimitProcessorTime(std::size_t file_bytes) {
  signal(SIGPROF, SIG_DFL);  // the default action ends the process
  const int ms = ProcessorMs(file_bytes);
  itimerval timer{};
  timer.it_value.tv_sec = ms / 1000;
  timer.it_value.tv_usec = (ms % 1000) * 1000;
  setitimer(ITIMER_PROF, &timer, nullptr);
}

// A read that takes longer than 5 s and 1 s per 4 MB of file by the clock is taken for HDF5 caught in a loop or
// waiting on something by a damaged file (Mx's largest exports, 16 MB, read in well under a second).
int LongestReadMs(std::size_t file_bytes) { return 5000 + static_cast<int>(file_bytes / (4u << 20)) * 1000; }

// ReadHere in a child process: its answer (or its error) comes back through a pipe.
bool Read(const std::string& bytes, std::uint64_t max_points, DatxContent* content, std::string* error) {
  static std::mutex hdf5_mutex;
  const std::lock_guard<std::mutex> lock(hdf5_mutex);
  // Initialised once here, so that every child starts with the library ready, quiet about errors.
  static const bool initialised = H5open() >= 0 && H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr) >= 0;
  if (!initialised) {
    *error = "the HDF5 library could not be initialised";
    return false;
  }
  if (std::string damaged = DamagedGlobalHeap(bytes); !damaged.empty()) {
    *error = damaged;  // refused before HDF5 loops or reads past its buffers on it
    return false;
  }
  const int longest_ms = LongestReadMs(bytes.size());
  int fds[2];
  if (pipe(fds) != 0) {
    *error = "no pipe for the HDF5 reader (too many open files?)";
    return false;
  }
  const pid_t child = fork();
  if (child < 0) {
    close(fds[0]), close(fds[1]);
    *error = "no process for the HDF5 reader (fork failed)";
    return false;
  }
  if (child == 0) {
    close(fds[0]);
    LimitProcessorTime(bytes.size());
    _exit(AnswerFromChild(bytes, max_points, fds[1]) ? 0 : 2);  // no exit handlers: they belong to the parent
  }
  close(fds[1]);
  std::string answer;
  bool timed_out = false;
  char buffer[1 << 16];
  for (;;) {
    pollfd ready{fds[0], POLLIN, 0};
    const int polled = poll(&ready, 1, longest_ms);
    if (polled == 0) {
      timed_out = true;
      kill(child, SIGKILL);
      break;
    }
    if (polled < 0) continue;  // interrupted by a signal
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n <= 0) break;
    answer.append(buffer, static_cast<std::size_t>(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(child, &status, 0) < 0) {
  }
  if (!timed_out && WIFSIGNALED(status) && WTERMSIG(status) == SIGPROF) {
    *error = "HDF5 did not finish reading it in " + std::to_string(ProcessorMs(bytes.size()) / 1000.0).substr(0, 4) +
             " s of processor time (a damaged HDF5 file)";
    return false;
  }
  if (timed_out || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    *error = timed_out ? "HDF5 did not finish reading it in " + std::to_string(longest_ms / 1000) +
                             " s (a damaged HDF5 file)"
                       : "HDF5 failed on it (the HDF5 library crashed reading a damaged HDF5 file)";
    return false;
  }
  if (!answer.empty() && answer[0] == '\0') {
    *error = answer.substr(1);
    return false;
  }
  if (!DecodeDatx(answer, content)) {
    *error = "the HDF5 reader's answer was cut short";
    return false;
  }
  return true;
}

constexpr DatxCodec kCodec{&Read};

}  // namespace
}  // namespace fvm::imaging

extern "C" __attribute__((visibility("default"))) const void* fvm_datx_codec_v1() { return &fvm::imaging::kCodec; }
