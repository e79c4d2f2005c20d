#include "server/png_encode.hpp"

#include <png.h>

#include <cstddef>
#include <stdexcept>
#include <string>

namespace server {

std::vector<std::uint8_t> encode_png_rgb(const std::vector<std::uint8_t>& rgb,
                                         int width,
                                         int height) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("png: image size " + std::to_string(width) + " x " +
                                std::to_string(height) + " must be positive");
  const std::size_t row_bytes = static_cast<std::size_t>(width) * 3;
  if (rgb.size() != row_bytes * static_cast<std::size_t>(height))
    throw std::invalid_argument("png: " + std::to_string(rgb.size()) + " bytes for a " +
                                std::to_string(width) + " x " + std::to_string(height) +
                                " RGB image (expected " + std::to_string(row_bytes * height) + ")");

  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = PNG_FORMAT_RGB;
  // speed over size: a thumbnail is encoded on every cache miss, and stays small either way
  image.flags = PNG_IMAGE_FLAG_FAST;

  // first call measures, second writes (the simplified API keeps libpng's longjmp inside)
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&image, nullptr, &size, /*convert_to_8bit=*/0, rgb.data(),
                                 static_cast<png_int_32>(row_bytes), nullptr)) {
    const std::string message = image.message;
    png_image_free(&image);
    throw std::runtime_error("png: libpng cannot encode the image: " + message);
  }
  std::vector<std::uint8_t> png(size);
  if (!png_image_write_to_memory(&image, png.data(), &size, 0, rgb.data(),
                                 static_cast<png_int_32>(row_bytes), nullptr)) {
    const std::string message = image.message;
    png_image_free(&image);
    throw std::runtime_error("png: libpng cannot encode the image: " + message);
  }
  png.resize(size);
  return png;
}

}  // namespace server
