#include "acquisition/pixel_format.h"

#include <cstring>

namespace irdist {
namespace {

// Pixel n of an LSB-first stream of `bits`-bit pixels (PFNC "p" formats).
void UnpackLsbFirst(const std::uint8_t* data, std::size_t count, int bits, std::uint16_t* out) {
  const std::uint32_t mask = (1u << bits) - 1u;
  for (std::size_t n = 0; n < count; ++n) {
    const std::size_t first_bit = n * static_cast<std::size_t>(bits);
    const std::size_t byte = first_bit / 8;
    const int shift = static_cast<int>(first_bit % 8);
    // A pixel of at most 12 bits starting at bit `shift` <= 7 spans at most 3 bytes, and only
    // the bytes holding its own bits are read (all inside the stream).
    std::uint32_t word = data[byte];
    if (shift + bits > 8) word |= static_cast<std::uint32_t>(data[byte + 1]) << 8;
    if (shift + bits > 16) word |= static_cast<std::uint32_t>(data[byte + 2]) << 16;
    out[n] = static_cast<std::uint16_t>((word >> shift) & mask);
  }
}

// GigE Vision Mono12Packed: [p0 bits 11-4][p1 bits 3-0 | p0 bits 3-0][p1 bits 11-4].
void UnpackGvMono12Packed(const std::uint8_t* data, std::size_t count, std::uint16_t* out) {
  for (std::size_t n = 0; n < count; ++n) {
    const std::uint8_t* group = data + (n / 2) * 3;
    if (n % 2 == 0) {
      out[n] = static_cast<std::uint16_t>((group[0] << 4) | (group[1] & 0x0f));
    } else {
      out[n] = static_cast<std::uint16_t>((group[2] << 4) | (group[1] >> 4));
    }
  }
}

}  // namespace

const std::vector<PixelFormatInfo>& SupportedPixelFormats() {
  static const std::vector<PixelFormatInfo> formats = {
      {"Mono8", 0x01080001u, 8, 8, false},
      {"Mono10", 0x01100003u, 10, 16, false},
      {"Mono10p", 0x010a0046u, 10, 10, true},
      {"Mono12", 0x01100005u, 12, 16, false},
      {"Mono12p", 0x010c0047u, 12, 12, true},
      {"Mono12Packed", 0x010c0006u, 12, 12, true},
      {"Mono14", 0x01100025u, 14, 16, false},
      {"Mono16", 0x01100007u, 16, 16, false},
  };
  return formats;
}

const PixelFormatInfo* FindPixelFormat(const std::string& name) {
  for (const auto& format : SupportedPixelFormats()) {
    if (format.name == name) return &format;
  }
  return nullptr;
}

const PixelFormatInfo* FindPixelFormat(std::uint32_t code) {
  for (const auto& format : SupportedPixelFormats()) {
    if (format.code == code) return &format;
  }
  return nullptr;
}

std::string SupportedPixelFormatNames() {
  std::string out;
  for (const auto& format : SupportedPixelFormats()) out += (out.empty() ? "" : ", ") + format.name;
  return out;
}

std::size_t ImageBytes(const PixelFormatInfo& format, int width, int height) {
  if (width <= 0 || height <= 0) return 0;
  const std::size_t bits = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                           static_cast<std::size_t>(format.bits_per_pixel);
  return (bits + 7) / 8;
}

cv::Mat UnpackMono(const PixelFormatInfo& format, const std::uint8_t* data, std::size_t size,
                   int width, int height) {
  const std::size_t needed = ImageBytes(format, width, height);
  if (data == nullptr || needed == 0 || size < needed) return cv::Mat();
  cv::Mat out(height, width, CV_16UC1);
  auto* pixels = out.ptr<std::uint16_t>();
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (format.bits_per_pixel == 8) {
    cv::Mat(height, width, CV_8UC1, const_cast<std::uint8_t*>(data)).convertTo(out, CV_16UC1);
  } else if (format.bits_per_pixel == 16) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    std::memcpy(pixels, data, count * 2);  // the wire's little-endian words as they are
#else
    for (std::size_t n = 0; n < count; ++n) {
      pixels[n] = static_cast<std::uint16_t>(data[2 * n] | (data[2 * n + 1] << 8));
    }
#endif
  } else if (format.name == "Mono12Packed") {
    UnpackGvMono12Packed(data, count, pixels);
  } else {
    UnpackLsbFirst(data, count, format.bits_per_pixel, pixels);
  }
  return out;
}

}  // namespace irdist
