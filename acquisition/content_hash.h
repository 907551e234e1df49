#pragma once
// Content hashes of a recording (docs/recording-format.md): the SHA-256 of each frame's PNG bytes
// in frames.csv, and of frames.csv itself in recording.yaml when the recording is closed, so that
// a swapped, replaced or edited file is found by check, fit and playback. OpenSSL's libcrypto.

#include <string>
#include <string_view>

namespace irdist {

// SHA-256 (FIPS 180-4) of `bytes` as 64 lowercase hex digits.
std::string Sha256Hex(std::string_view bytes);

// Whether `text` has the form of Sha256Hex's result (64 lowercase hex digits).
bool IsSha256Hex(std::string_view text);

}  // namespace irdist
