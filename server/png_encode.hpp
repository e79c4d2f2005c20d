// PNG encoding of 8-bit RGB images through libpng's simplified write API (libpng ≥ 1.6.29).
#pragma once

#include <cstdint>
#include <vector>

namespace server {

/// The PNG file bytes of a width × height RGB image; `rgb` holds rows top to bottom, 3 bytes per
/// pixel, no padding.
/// @throws std::invalid_argument when the size is not positive or `rgb` has the wrong length
/// @throws std::runtime_error with libpng's message when encoding fails
std::vector<std::uint8_t> encode_png_rgb(const std::vector<std::uint8_t>& rgb,
                                         int width,
                                         int height);

}  // namespace server
