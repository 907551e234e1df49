#pragma once
// Test helper: waits until UDP 127.0.0.1:3956 (GVCP) is free, since only one fake GigE camera
// can serve loopback at a time and other modules' tests may hold it for a while.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>

namespace irdist::sim::testing {

inline bool GvcpPortFreeNow() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return false;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(3956);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0;
  ::close(fd);
  return ok;
}

inline bool WaitForGvcpPort(std::chrono::seconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!GvcpPortFreeNow()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return true;
}

}  // namespace irdist::sim::testing
