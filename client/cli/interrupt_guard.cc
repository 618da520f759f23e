#include "client/cli/interrupt_guard.h"

#include <signal.h>

#include <csignal>

#include "client/io/temporary_files.h"

namespace tetrefine::cli {
namespace {

constexpr int kSignals = 3;
constexpr int kHandled[kSignals] = {SIGINT, SIGTERM, SIGHUP};

volatile std::sig_atomic_t g_interrupted = 0;  // the first signal caught, or 0
// Which of kHandled the live guard handles (not those ignored at start); read by the handler.
volatile std::sig_atomic_t g_handled[kSignals] = {};
struct sigaction g_previous[kSignals] = {};

extern "C" void OnInterrupt(int signal_number) {
  if (g_interrupted == 0) g_interrupted = signal_number;
  // The next one, whichever it is, ends the process (sigaction is async-signal-safe). Were only
  // this signal's action reset, a different second signal would be recorded and ignored.
  for (int i = 0; i < kSignals; ++i) {
    if (g_handled[i] != 0) io::RemoveTemporariesOnSignal(kHandled[i]);
  }
}

}  // namespace

InterruptGuard::InterruptGuard() {
  g_interrupted = 0;
  struct sigaction action = {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  // Every handled signal is blocked while the handler runs, so that two arriving together are
  // taken one after the other: the first recorded, the second ending the process.
  for (const int signal_number : kHandled) sigaddset(&action.sa_mask, signal_number);
  for (int i = 0; i < kSignals; ++i) {
    g_handled[i] = sigaction(kHandled[i], nullptr, &g_previous[i]) == 0 &&
                   g_previous[i].sa_handler != SIG_IGN &&
                   sigaction(kHandled[i], &action, nullptr) == 0;
  }
}

InterruptGuard::~InterruptGuard() {
  for (int i = 0; i < kSignals; ++i) {
    if (g_handled[i] != 0) sigaction(kHandled[i], &g_previous[i], nullptr);
    g_handled[i] = 0;
  }
}

int InterruptGuard::Interrupted() { return g_interrupted; }

std::string InterruptGuard::InterruptedBy() {
  switch (g_interrupted) {
    case 0:
      return "";
    case SIGINT:
      return "interrupted";
    case SIGTERM:
      return "terminated (SIGTERM)";
    default:
      return "hung up (SIGHUP)";
  }
}

}  // namespace tetrefine::cli
