// libFuzzer target: a rig file with its `station.devices:` entries checked by every registered
// driver's validate() (zaber_ascii, flir_ptu, scpi_source, irdist_station are all linked here), then
// the trigger check of a plan. Nothing is opened. Every refusal must be an InputError (RecipeError)
// naming the rig file; an accepted one lies inside the bounds table (fuzz/in_bounds.h).
#include <cstddef>
#include <cstdint>
#include <string>

#include "app/inputs/errors.h"
#include "app/inputs/rig.h"
#include "fuzz/in_bounds.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const irdist::Rig rig = irdist::ParseRig(text, "fuzz-rig.yaml");
    if (!irdist::fuzz::RigInBounds(rig)) __builtin_trap();
    irdist::CheckTriggerSettings(rig);
  } catch (const irdist::InputError& error) {
    if (error.File() != "fuzz-rig.yaml") __builtin_trap();
  }
  return 0;
}
