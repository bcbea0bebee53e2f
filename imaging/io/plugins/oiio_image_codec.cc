// The image codec on OpenImageIO, built as the plugin libfvm_image_oiio.so (see imaging/io/image_codec.h). Nothing
// here validates or explains: the callers do, in fvm_imaging. Every failure, exceptions included, comes back as
// text, so that no exception has to cross the plugin boundary.

#include <OpenImageIO/imageio.h>

#include <exception>
#include <memory>
#include <string>

#include "imaging/io/image_codec.h"

namespace fvm::imaging {
namespace {

OIIO::TypeDesc ToOiio(PixelType type) {
  switch (type) {
    case PixelType::kUint8: return OIIO::TypeDesc::UINT8;
    case PixelType::kInt8: return OIIO::TypeDesc::INT8;
    case PixelType::kUint16: return OIIO::TypeDesc::UINT16;
    case PixelType::kInt16: return OIIO::TypeDesc::INT16;
    case PixelType::kUint32: return OIIO::TypeDesc::UINT32;
    case PixelType::kInt32: return OIIO::TypeDesc::INT32;
    case PixelType::kDouble: return OIIO::TypeDesc::DOUBLE;
    default: return OIIO::TypeDesc::FLOAT;
  }
}

PixelType FromOiio(OIIO::TypeDesc type) {
  switch (type.basetype) {
    case OIIO::TypeDesc::UINT8: return PixelType::kUint8;
    case OIIO::TypeDesc::INT8: return PixelType::kInt8;
    case OIIO::TypeDesc::UINT16: return PixelType::kUint16;
    case OIIO::TypeDesc::INT16: return PixelType::kInt16;
    case OIIO::TypeDesc::UINT32: return PixelType::kUint32;
    case OIIO::TypeDesc::INT32: return PixelType::kInt32;
    case OIIO::TypeDesc::FLOAT: return PixelType::kFloat;
    case OIIO::TypeDesc::DOUBLE: return PixelType::kDouble;
    default: return PixelType::kOther;
  }
}

class OiioReader final : public ImageFileReader {
 public:
  explicit OiioReader(std::unique_ptr<OIIO::ImageInput> input, int subimage = 0)
      : input_(std::move(input)), subimage_(subimage) {
    const OIIO::ImageSpec& spec = input_->spec();
    header_.width = spec.width;
    header_.height = spec.height;
    header_.depth = spec.depth;
    header_.channels = spec.nchannels;
    header_.alpha_channel = spec.alpha_channel;
    header_.type = FromOiio(spec.format);
    header_.type_name = spec.format.c_str();
    header_.format_name = input_->format_name();
    header_.description = spec.get_string_attribute("ImageDescription");
    header_.resolution_unit = spec.get_string_attribute("ResolutionUnit");
    header_.x_resolution = spec.get_float_attribute("XResolution", 0.0f);
    header_.y_resolution = spec.get_float_attribute("YResolution", 0.0f);
    header_.rows_per_strip = spec.get_int_attribute("tiff:RowsPerStrip", 0);
  }
  ~OiioReader() override { input_->close(); }

  const ImageHeader& Header() const override { return header_; }

  bool ReadPixels(int first_channel, int end_channel, PixelType as, void* data, std::string* error) override {
    try {
      const bool read = input_->read_image(subimage_, 0, first_channel, end_channel, ToOiio(as), data);
      *error = input_->geterror();
      return read;
    } catch (const std::exception& e) {
      *error = e.what();
      return false;
    }
  }

 private:
  std::unique_ptr<OIIO::ImageInput> input_;
  int subimage_;
  ImageHeader header_;
};

std::unique_ptr<ImageFileReader> Open(const std::filesystem::path& path, std::string* error) {
  try {
    std::unique_ptr<OIIO::ImageInput> input = OIIO::ImageInput::open(path.string());
    if (!input) {
      *error = OIIO::geterror();
      return nullptr;
    }
    return std::make_unique<OiioReader>(std::move(input));
  } catch (const std::exception& e) {
    *error = e.what();
    return nullptr;
  }
}

std::unique_ptr<ImageFileReader> OpenSubimage(const std::filesystem::path& path, int subimage, std::string* error) {
  try {
    std::unique_ptr<OIIO::ImageInput> input = OIIO::ImageInput::open(path.string());
    if (!input) {
      *error = OIIO::geterror();
      return nullptr;
    }
    if (!input->seek_subimage(subimage, 0)) {
      *error = "no image " + std::to_string(subimage) + " in the file";
      input->close();
      return nullptr;
    }
    return std::make_unique<OiioReader>(std::move(input), subimage);
  } catch (const std::exception& e) {
    *error = e.what();
    return nullptr;
  }
}

ImageWriteResult Write(const std::filesystem::path& path, const ImageWriteSpec& request, PixelType data_type,
                       const void* data, std::string* error) {
  try {
    OIIO::ImageSpec spec(request.width, request.height, request.channels, ToOiio(request.type));
    spec.alpha_channel = request.alpha_channel;
    if (!request.description.empty()) spec.attribute("ImageDescription", request.description);
    if (!request.resolution_unit.empty()) {
      spec.attribute("XResolution", request.x_resolution);
      spec.attribute("YResolution", request.y_resolution);
      spec.attribute("ResolutionUnit", request.resolution_unit);
    }
    std::unique_ptr<OIIO::ImageOutput> output = OIIO::ImageOutput::create(path.string());
    if (!output) {
      *error = OIIO::geterror();
      return ImageWriteResult::kUnknownFormat;
    }
    if (!output->open(path.string(), spec) || !output->write_image(ToOiio(data_type), data) || !output->close()) {
      *error = output->geterror();
      return ImageWriteResult::kFailed;
    }
    return ImageWriteResult::kWritten;
  } catch (const std::exception& e) {
    *error = e.what();
    return ImageWriteResult::kFailed;
  }
}

constexpr ImageCodec kCodec{&Open, &Write, &OpenSubimage};

}  // namespace
}  // namespace fvm::imaging

extern "C" __attribute__((visibility("default"))) const void* fvm_image_codec_v1() { return &fvm::imaging::kCodec; }
