// irdist: turns the library's typed errors into exit codes and one clear message each.
#include <csignal>
#include <exception>
#include <iostream>

#include <glog/logging.h>

#include "app/cli/cli.h"

int main(int argc, char** argv) {
  // Ceres logs through glog; a failed trial step of one calibration start ("consecutive invalid
  // steps") is an ERROR line there, while the fit already reports each model's termination. Keep
  // the terminal for irdist's own messages.
  FLAGS_minloglevel = google::GLOG_FATAL;
  // A reader that goes away (`irdist ... | head`) is a failed write (EPIPE), not a kill, in every
  // command (GLib's sockets already make it so where a camera is opened): measure stops on it
  // with its summary; calibrate, validate and playback finish their run folder and exit 0.
  if (std::signal(SIGPIPE, SIG_IGN) == SIG_ERR) {
    std::cerr << "irdist: warning: SIGPIPE cannot be ignored; a closed pipe will end the command\n";
  }
  try {
    return irdist::RunIrdist(argc, argv, {std::cout, std::cerr});
  } catch (const irdist::UsageError& e) {
    std::cerr << "irdist: " << e.what() << "\n";
    return 2;
  } catch (const irdist::InterruptedError& e) {
    std::cerr << "irdist: " << e.what() << "\n";
    return 130;
  } catch (const irdist::Error& e) {
    std::cerr << "irdist: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "irdist: unexpected error: " << e.what() << "\n";
    return 1;
  }
}
