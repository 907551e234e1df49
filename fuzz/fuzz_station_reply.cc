// libFuzzer target: one line from the station, as the client decodes it (station/frame.h).
// Malformed lines must come back as nullopt with a reason, never crash or hang.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "station/frame.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  std::string why;
  const auto reply = irdist::DecodeReply(line, &why);
  if (!reply && why.empty()) __builtin_trap();  // a refusal always says why
  return 0;
}
