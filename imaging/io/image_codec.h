#pragma once
// Image files behind a small std-typed interface, so that fvm_imaging does not link OpenImageIO: the codec lives
// in the plugin libfvm_image_oiio.so (imaging/io/plugins/oiio_image_codec.cc), loaded the first time a command
// reads or writes an image. Loading OpenImageIO costs a third of a second and 130 MB, which commands that never
// touch an image (calibrate, compare, diff, ...) should not pay.
//
// The plugin never throws: it reports failures as text, and the callers (height_map_image.cc, tile_image.cc,
// focus_stack_io.cc) turn them into InputError naming the file and what to do.

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace fvm::imaging {

enum class PixelType { kUint8, kInt8, kUint16, kInt16, kUint32, kInt32, kFloat, kDouble, kOther };

constexpr bool IsIntegerPixelType(PixelType type) {
  return type == PixelType::kUint8 || type == PixelType::kInt8 || type == PixelType::kUint16 ||
         type == PixelType::kInt16 || type == PixelType::kUint32 || type == PixelType::kInt32;
}

// What an image file says about itself, before any pixel is read (so that a damaged header can be refused
// before it makes us allocate).
struct ImageHeader {
  int width = 0, height = 0, depth = 1, channels = 0;
  int alpha_channel = -1;          // -1: none
  PixelType type = PixelType::kOther;
  std::string type_name;           // "uint16", "float", ... for messages
  std::string format_name;         // "tiff", "png", ...
  std::string description;         // the ImageDescription text, empty when absent
  std::string resolution_unit;     // "cm", "in", ... empty when absent
  float x_resolution = 0.0f;       // pixels per resolution unit, 0 when absent
  float y_resolution = 0.0f;
  int rows_per_strip = 0;          // TIFF in strips: rows per strip (as the file says); 0 otherwise
};

// One open image file.
class ImageFileReader {
 public:
  virtual ~ImageFileReader() = default;
  virtual const ImageHeader& Header() const = 0;
  // Channels [first, end) of every pixel, interleaved, converted to `as` into `data` (width * height * (end -
  // first) values). Integer pixels read as float or double come back scaled to 0..1, as OpenImageIO does.
  // Returns false when the read failed; `error` receives any error the library reported, even on success (a
  // truncated TIFF strip is reported only there).
  virtual bool ReadPixels(int first_channel, int end_channel, PixelType as, void* data, std::string* error) = 0;
};

// What to write: one image of `channels` channels in `type`, with optional metadata.
struct ImageWriteSpec {
  int width = 0, height = 0, channels = 1;
  int alpha_channel = -1;  // -1: none
  PixelType type = PixelType::kFloat;
  std::string description;      // empty: none
  std::string resolution_unit;  // empty: no resolution
  float x_resolution = 0.0f, y_resolution = 0.0f;
};

enum class ImageWriteResult { kWritten, kUnknownFormat, kFailed };

// The plugin's function table (entry point "fvm_image_codec_v1").
struct ImageCodec {
  // nullptr and `error` set when the file cannot be opened as an image.
  std::unique_ptr<ImageFileReader> (*open)(const std::filesystem::path& path, std::string* error);
  // Writes `data` (in `data_type`, interleaved) to `path`, the format chosen by the path's extension.
  ImageWriteResult (*write)(const std::filesystem::path& path, const ImageWriteSpec& spec, PixelType data_type,
                            const void* data, std::string* error);
  // The image `subimage` (0 first) of a multi-image file (the pages of a TIFF); nullptr and `error` set when the
  // file cannot be opened or has no such image.
  std::unique_ptr<ImageFileReader> (*open_subimage)(const std::filesystem::path& path, int subimage,
                                                    std::string* error);
};

// The codec, loading the plugin on first use. `action` says what needed it ("reading scan.tif"); when the
// plugin cannot be loaded, throws InputError "<action> needs OpenImageIO: ... could not be loaded (...);
// install the Debian package ...".
const ImageCodec& LoadImageCodec(std::string_view action);

// Writes `data` (in `data_type`, interleaved) to `path` through the codec, atomically (a temporary file renamed
// over it). Throws InputError naming `path` when the format is unknown or the write fails.
void WriteImageFile(const std::filesystem::path& path, const ImageWriteSpec& spec, PixelType data_type,
                    const void* data);

// Throws InputError naming `path` when its header claims more pixel bytes than a file of `file_bytes` could hold
// decompressed (deflate and LZW stay under about 1:1000; we allow 1:4096, and never refuse below 64 MiB): a
// damaged header must not make a reader allocate gigabytes.
void CheckPixelsFitFile(const std::filesystem::path& path, const ImageHeader& header, std::size_t file_bytes);

}  // namespace fvm::imaging
