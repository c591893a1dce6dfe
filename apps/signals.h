#pragma once
// Servers stop cleanly on SIGTERM or SIGINT: the signals are blocked in every thread (call
// block_stop_signals() before starting any), and the main thread waits for one.
#include <csignal>
#include <pthread.h>

namespace meshflow::apps {

inline sigset_t stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  return set;
}

inline void block_stop_signals() {
  sigset_t set = stop_signals();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

// Blocks until SIGTERM or SIGINT arrives; returns the signal.
inline int wait_for_stop_signal() {
  sigset_t set = stop_signals();
  int signal = 0;
  sigwait(&set, &signal);
  return signal;
}

}  // namespace meshflow::apps
