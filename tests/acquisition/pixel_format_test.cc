// Tests of acquisition/pixel_format.cc: packed pixel formats unpacked to their 16-bit values,
// against byte vectors written by hand from the standards' bit layouts (PFNC Mono10p / Mono12p:
// LSB-first bit stream; GigE Vision Mono12Packed: two pixels in three bytes, the 8 high bits of
// each in its own byte and the two low nibbles shared), and against a bit-by-bit packer of the
// PFNC rule over every value of a random image.
#include "acquisition/pixel_format.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace irdist {
namespace {

std::vector<std::uint16_t> Unpack(const char* name, const std::vector<std::uint8_t>& bytes,
                                  int width, int height) {
  const PixelFormatInfo* format = FindPixelFormat(name);
  EXPECT_NE(format, nullptr) << name;
  if (format == nullptr) return {};
  const cv::Mat image = UnpackMono(*format, bytes.data(), bytes.size(), width, height);
  if (image.empty()) return {};
  EXPECT_EQ(image.type(), CV_16UC1);
  return std::vector<std::uint16_t>(image.begin<std::uint16_t>(), image.end<std::uint16_t>());
}

TEST(PixelFormat, Mono12pIsLsbFirstTwoPixelsInThreeBytes) {
  // 0xABC then 0x123: byte 0 = 0xBC (p0 bits 0-7), byte 1 = p1 bits 0-3 | p0 bits 8-11 = 0x3A,
  // byte 2 = p1 bits 4-11 = 0x12.
  EXPECT_EQ(Unpack("Mono12p", {0xBC, 0x3A, 0x12}, 2, 1),
            (std::vector<std::uint16_t>{0xABC, 0x123}));
  // Three pixels (36 bits, 5 bytes): the third starts byte 3.
  EXPECT_EQ(Unpack("Mono12p", {0xFF, 0x0F, 0x00, 0x01, 0x08}, 3, 1),
            (std::vector<std::uint16_t>{0xFFF, 0x000, 0x801}));
}

TEST(PixelFormat, Mono12PackedSharesTheLowNibblesInTheMiddleByte) {
  // 0xABC then 0x123: byte 0 = p0 bits 4-11 = 0xAB, byte 1 = p1 bits 0-3 << 4 | p0 bits 0-3 = 0x3C,
  // byte 2 = p1 bits 4-11 = 0x12.
  EXPECT_EQ(Unpack("Mono12Packed", {0xAB, 0x3C, 0x12}, 2, 1),
            (std::vector<std::uint16_t>{0xABC, 0x123}));
  // The same bytes mean other values in Mono12p: the two layouts are not interchangeable.
  EXPECT_NE(Unpack("Mono12p", {0xAB, 0x3C, 0x12}, 2, 1),
            (std::vector<std::uint16_t>{0xABC, 0x123}));
}

TEST(PixelFormat, Mono10pIsLsbFirstFourPixelsInFiveBytes) {
  // 0x3FF, 0x000, 0x155, 0x2AA as a 40-bit LSB-first stream.
  EXPECT_EQ(Unpack("Mono10p", {0xFF, 0x03, 0x50, 0x95, 0xAA}, 2, 2),
            (std::vector<std::uint16_t>{0x3FF, 0x000, 0x155, 0x2AA}));
}

TEST(PixelFormat, UnpackedFormatsAreBytesOrLittleEndianWords) {
  EXPECT_EQ(Unpack("Mono8", {0, 200}, 2, 1), (std::vector<std::uint16_t>{0, 200}));
  EXPECT_EQ(Unpack("Mono16", {0x34, 0x12, 0xff, 0xff}, 2, 1),
            (std::vector<std::uint16_t>{0x1234, 0xffff}));
  EXPECT_EQ(Unpack("Mono12", {0xff, 0x0f}, 1, 1), (std::vector<std::uint16_t>{0x0fff}));
}

// Packs `values` of `bits` bits LSB-first, one bit at a time (the PFNC definition).
std::vector<std::uint8_t> PackLsbFirst(const std::vector<std::uint16_t>& values, int bits) {
  std::vector<std::uint8_t> out((values.size() * bits + 7) / 8, 0);
  std::size_t k = 0;
  for (std::uint16_t value : values) {
    for (int b = 0; b < bits; ++b, ++k) {
      if ((value >> b) & 1) out[k / 8] = static_cast<std::uint8_t>(out[k / 8] | (1 << (k % 8)));
    }
  }
  return out;
}

TEST(PixelFormat, EveryValueOfARandomOddSizedImageComesBack) {
  std::mt19937 rng(5);
  for (const int bits : {10, 12}) {
    const int width = 13, height = 7;  // an odd pixel count: the stream ends mid-byte
    std::vector<std::uint16_t> values(width * height);
    for (auto& value : values) value = static_cast<std::uint16_t>(rng() & ((1u << bits) - 1));
    const char* name = bits == 10 ? "Mono10p" : "Mono12p";
    const std::vector<std::uint8_t> bytes = PackLsbFirst(values, bits);
    EXPECT_EQ(bytes.size(), ImageBytes(*FindPixelFormat(name), width, height));
    EXPECT_EQ(Unpack(name, bytes, width, height), values) << name;
  }
}

TEST(PixelFormat, ShortPayloadOrUnknownNameIsRefused) {
  const PixelFormatInfo* mono12p = FindPixelFormat("Mono12p");
  ASSERT_NE(mono12p, nullptr);
  const std::vector<std::uint8_t> bytes = {1, 2};
  EXPECT_TRUE(UnpackMono(*mono12p, bytes.data(), bytes.size(), 2, 1).empty());
  EXPECT_EQ(FindPixelFormat("mono12p"), nullptr);  // GenICam names are case-sensitive
  EXPECT_EQ(FindPixelFormat("RGB8"), nullptr);
  EXPECT_EQ(FindPixelFormat(0x010c0047u)->name, "Mono12p");
  EXPECT_EQ(FindPixelFormat(0x010c0006u)->name, "Mono12Packed");
  EXPECT_EQ(FindPixelFormat(0x010a0046u)->bit_depth, 10);
}

}  // namespace
}  // namespace irdist
