#include "station/frame.h"

#include <boost/crc.hpp>
#include <cstdio>

#include "base/check.h"

namespace irdist {

// CRC-8/SMBUS: width 8, polynomial 0x07, initial 0x00, no reflection, no final xor.
std::uint8_t Crc8(std::string_view text) {
  boost::crc_optimal<8, 0x07, 0x00, 0x00, false, false> crc;
  crc.process_bytes(text.data(), text.size());
  return static_cast<std::uint8_t>(crc.checksum());
}

std::string EncodeRequest(int seq, std::string_view command) {
  IRDIST_CHECK(seq >= 0 && seq <= kMaxSequence, "sequence number ", seq);
  IRDIST_CHECK(!command.empty(), "empty command");
  for (char c : command) {
    IRDIST_CHECK(c >= 0x20 && c < 0x7F && c != '#', "unprintable or reserved byte in ",
                 std::string(command));
  }
  std::string text = "#" + std::to_string(seq) + " " + std::string(command);
  char cs[4];
  std::snprintf(cs, sizeof(cs), "%02X", Crc8(text));
  return text + "*" + cs;
}

namespace {
int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}
}  // namespace

std::optional<Reply> DecodeReply(std::string_view line, std::string* why) {
  auto fail = [&](const char* m) -> std::optional<Reply> {
    if (why) *why = m;
    return std::nullopt;
  };
  for (char c : line) {
    if (c < 0x20 || c >= 0x7F) return fail("unprintable byte");
  }
  if (line.size() < 7 || line[0] != '#') return fail("does not start with '#'");
  const std::size_t star = line.size() - 3;
  if (line[star] != '*') return fail("no '*<hh>' checksum at the end");
  const int hi = HexDigit(line[star + 1]);
  const int lo = HexDigit(line[star + 2]);
  if (hi < 0 || lo < 0) return fail("checksum is not two hex digits");
  const std::string_view text = line.substr(0, star);
  if (Crc8(text) != hi * 16 + lo) return fail("checksum mismatch");
  const std::size_t space = text.find(' ');
  if (space == std::string_view::npos || space < 2 || space > 5) return fail("bad sequence field");
  Reply reply;
  reply.seq = 0;
  for (std::size_t i = 1; i < space; ++i) {
    if (text[i] < '0' || text[i] > '9') return fail("sequence is not a number");
    reply.seq = reply.seq * 10 + (text[i] - '0');
  }
  const std::string_view body = text.substr(space + 1);
  if (body == "OK") {
    reply.ok = true;
    return reply;
  }
  if (body.substr(0, 3) == "OK ") {
    reply.ok = true;
    reply.payload = std::string(body.substr(3));
    return reply;
  }
  if (body.substr(0, 4) == "ERR ") {
    const std::string_view rest = body.substr(4);
    const std::size_t comma = rest.find(',');
    const std::string code(rest.substr(0, comma));
    const bool has_digit = code.find_first_of("0123456789") != std::string::npos;
    if (!has_digit || code.size() > 6) return fail("bad error code");
    for (std::size_t i = 0; i < code.size(); ++i) {
      if (!((code[i] >= '0' && code[i] <= '9') || (i == 0 && code[i] == '-'))) {
        return fail("bad error code");
      }
    }
    reply.error_code = std::stoi(code);
    if (comma != std::string_view::npos) {
      std::string text_part(rest.substr(comma + 1));
      if (text_part.size() >= 2 && text_part.front() == '"' && text_part.back() == '"') {
        text_part = text_part.substr(1, text_part.size() - 2);
      }
      reply.error_text = text_part;
    }
    return reply;
  }
  return fail("reply is neither OK nor ERR");
}

}  // namespace irdist
