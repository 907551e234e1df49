// irdist: turns the library's typed errors into exit codes and one clear message each.
#include <exception>
#include <iostream>

#include <glog/logging.h>

#include "app/cli.h"

int main(int argc, char** argv) {
  // Ceres logs through glog; a failed trial step of one calibration start ("consecutive invalid
  // steps") is an ERROR line there, while the fit already reports each model's termination. Keep
  // the terminal for irdist's own messages.
  FLAGS_minloglevel = google::GLOG_FATAL;
  try {
    return irdist::RunIrdist(argc, argv, {std::cout, std::cerr});
  } catch (const irdist::UsageError& e) {
    std::cerr << "irdist: " << e.what() << "\n";
    return 2;
  } catch (const irdist::InterruptedError& e) {
    std::cerr << "irdist: " << e.what() << "\n";
    return 130;
  } catch (const irdist::NotAvailableError& e) {
    std::cerr << "irdist: " << e.what() << "\n";
    return 2;
  } catch (const irdist::Error& e) {
    std::cerr << "irdist: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "irdist: unexpected error: " << e.what() << "\n";
    return 1;
  }
}
