#pragma once
// Framing of the station protocol (docs/station-protocol.md): requests "#<seq> <command>*<hh>",
// replies "#<seq> OK[ <payload>]*<hh>" or "#<seq> ERR <code>,\"<message>\"*<hh>", where <hh> is
// the CRC-8 (poly 0x07, init 0) of every byte before '*', as two hex digits.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace irdist {

constexpr int kMaxSequence = 9999;  // sequence numbers run 0..9999 and wrap

// CRC-8, polynomial 0x07, initial value 0x00, no reflection, no final xor.
std::uint8_t Crc8(std::string_view text);

// "#<seq> <command>*<hh>" (without line end). IRDIST_CHECKs seq range and printable command.
std::string EncodeRequest(int seq, std::string_view command);

struct Reply {
  int seq = -1;
  bool ok = false;
  std::string payload;      // after "OK " (may be empty)
  int error_code = 0;       // for ERR replies
  std::string error_text;   // for ERR replies
};

// Parses and verifies one reply line; nullopt (and `why`) when it is malformed or its checksum
// does not match.
std::optional<Reply> DecodeReply(std::string_view line, std::string* why);

}  // namespace irdist
