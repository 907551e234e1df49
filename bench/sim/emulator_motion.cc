// The device emulators over their ptys: wall time of a move polled until idle, as a ratio to the
// move's physical bound (its trapezoidal profile at the time scale), and the round trip of one
// query. Run: ./build/bench/sim/bench_emulator_motion

#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include "sim/device_emulator.h"
#include "sim/world.h"

namespace irdist::sim {
namespace {

constexpr double kTimeScale = 10.0;

const char* const kRig =
    "station:\n  devices:\n    slide:\n      driver: zaber_ascii\n      port: auto\n"
    "      axes: {slide: \"1 1\"}\n      origin_mm: 1000.0\n"
    "virtual:\n  devices:\n    slide:\n      maxspeed_mm_s: 250\n      accel_mm_s2: 1000\n";

class Host {
 public:
  explicit Host(const std::string& path) : fd_(::open(path.c_str(), O_RDWR | O_NOCTTY)) {
    termios tio{};
    if (fd_ >= 0 && tcgetattr(fd_, &tio) == 0) {
      cfmakeraw(&tio);
      tcsetattr(fd_, TCSANOW, &tio);
    }
  }
  ~Host() {
    if (fd_ >= 0) ::close(fd_);
  }
  std::string Ask(const std::string& line) {
    if (::write(fd_, line.data(), line.size()) != static_cast<ssize_t>(line.size())) return "";
    std::string reply;
    while (reply.find('\n') == std::string::npos) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 2000) <= 0) return "";
      char buf[256];
      const ssize_t n = ::read(fd_, buf, sizeof(buf));
      if (n > 0) reply.append(buf, static_cast<std::size_t>(n));
    }
    return reply;
  }

 private:
  int fd_;
};

// 500 mm at 250 mm/s and 1000 mm/s^2: 0.25 s ramps + 1.75 s cruise = 2.25 s simulated.
void BM_ZaberMoveAgainstItsBound(benchmark::State& state) {
  World world(kTimeScale);
  auto emulator = FindEmulator("zaber_ascii")->create(
      world, EmulatorSpec{"slide", "zaber_ascii", "bench", kRig, 1});
  Host host(emulator->Start());
  const double bound_s = 2.25 / kTimeScale;
  long target = 0;
  double wall_s = 0.0;
  for (auto _ : state) {
    target = target == 0 ? 5039370 : 0;  // 500 mm of 0.09921875 um microsteps
    const auto start = std::chrono::steady_clock::now();
    host.Ask("/1 1 move abs " + std::to_string(target) + "\n");
    while (host.Ask("/1 1\n").find("IDLE") == std::string::npos) {
    }
    wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  state.counters["wall_over_bound"] = wall_s / (bound_s * state.iterations());
}
BENCHMARK(BM_ZaberMoveAgainstItsBound)->Iterations(6)->Unit(benchmark::kMillisecond);

void BM_ScpiQueryRoundTrip(benchmark::State& state) {
  World world(kTimeScale);
  auto emulator = FindEmulator("scpi_source")->create(
      world, EmulatorSpec{"source", "scpi_source", "bench", "", 1});
  Host host(emulator->Start());
  for (auto _ : state) benchmark::DoNotOptimize(host.Ask("*OPC?\n"));
}
BENCHMARK(BM_ScpiQueryRoundTrip)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace irdist::sim

BENCHMARK_MAIN();
