#pragma once
// The monochrome pixel formats irdist takes from a camera, and their unpacking to 16-bit values.
//
// Unpacked formats (Mono8, Mono10, Mono12, Mono14, Mono16) carry one pixel per byte or per
// little-endian 16-bit word. Packed ones carry a continuous bit stream over the whole image:
// - Mono10p, Mono12p (GenICam PFNC): LSB-first. Pixel n occupies bits [n b, (n + 1) b) of the
//   stream, where bit k is bit (k mod 8) of byte k / 8: Mono12p puts pixel 0 in byte 0 and the low
//   nibble of byte 1, pixel 1 in the high nibble of byte 1 and byte 2.
// - Mono12Packed (GigE Vision 1.x, GVSP_PIX_MONO12_PACKED): two pixels in three bytes, byte 0 the
//   8 most significant bits of pixel 0, byte 2 those of pixel 1, byte 1 their 4 least significant
//   bits (pixel 0 in bits 0-3, pixel 1 in bits 4-7).
// The values are never rescaled: a Mono12p pixel of 4095 unpacks to 4095.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace irdist {

struct PixelFormatInfo {
  std::string name;        // GenICam PixelFormat entry, e.g. "Mono12p"
  std::uint32_t code = 0;  // PFNC / GigE Vision pixel format value sent in the GVSP leader
  int bit_depth = 0;       // significant bits per pixel
  int bits_per_pixel = 0;  // bits each pixel occupies in the payload
  bool packed = false;     // a continuous bit stream (bits_per_pixel not a multiple of 8)
};

// Every monochrome format irdist accepts, in the order a rig file lists them.
const std::vector<PixelFormatInfo>& SupportedPixelFormats();
// The format named `name` (GenICam spelling, case-sensitive), or nullptr.
const PixelFormatInfo* FindPixelFormat(const std::string& name);
// The format sent with pixel format value `code` in a GVSP leader, or nullptr.
const PixelFormatInfo* FindPixelFormat(std::uint32_t code);
// "Mono8, Mono10, ..." for messages.
std::string SupportedPixelFormatNames();

// Bytes of one width x height image in `format` (packed formats rounded up to a whole byte).
std::size_t ImageBytes(const PixelFormatInfo& format, int width, int height);

// The image in `data` (`size` bytes, at least ImageBytes) as CV_16UC1 with the values sent.
// Returns an empty Mat when `size` is too small or the dimensions are not positive.
cv::Mat UnpackMono(const PixelFormatInfo& format, const std::uint8_t* data, std::size_t size,
                   int width, int height);

}  // namespace irdist
