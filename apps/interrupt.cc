// SIGINT/SIGTERM of a long command: apps/interrupt.h.
#include "apps/interrupt.h"

#include <dirent.h>
#include <fcntl.h>
#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>
#include <string>

namespace occgt {
namespace {

// Fixed before the handler is installed (the message) or before g_registered is set (the
// names), never changed after: the handler only reads them.
std::string g_message;  // "\noccgt: interrupted; <advice>\n"
TemporaryNames g_names;
std::atomic<bool> g_registered{false};
// 0: signals act at once; 1: held (HoldInterrupts); -S: signal S came while held.
std::atomic<int> g_hold{0};
static_assert(std::atomic<int>::is_always_lock_free, "the handler needs lock-free atomics");

// Async-signal-safe (strlen and memcmp only).
bool Matches(const char* name, const TemporaryNames& names) {
  const size_t n = std::strlen(name);
  for (const std::string& whole : names.names) {
    if (n == whole.size() && std::memcmp(name, whole.data(), n) == 0) return true;
  }
  for (const std::string& end : names.suffixes) {
    if (n > end.size() && std::memcmp(name + n - end.size(), end.data(), end.size()) == 0) {
      return true;
    }
  }
  return false;
}

// Removes the files of the folder open as `dir_fd` that `names` matches (null: every file);
// async-signal-safe (getdents64 and unlinkat are system calls). Entries removed while the
// folder is listed may make the listing skip others: passes repeat until one removes nothing.
int RemoveMatching(int dir_fd, const TemporaryNames* names) {
  int removed = 0;
  for (int pass = 0; pass < 8; ++pass) {
    int this_pass = 0;
    if (::lseek(dir_fd, 0, SEEK_SET) != 0) break;
    alignas(8) char buffer[8192];
    for (;;) {
      const ssize_t got = ::getdents64(dir_fd, buffer, sizeof(buffer));
      if (got <= 0) break;
      for (ssize_t at = 0; at < got;) {
        const auto* entry = reinterpret_cast<const struct dirent64*>(buffer + at);
        at += entry->d_reclen;
        if (entry->d_type == DT_DIR || (names != nullptr && !Matches(entry->d_name, *names))) {
          continue;
        }
        if (::unlinkat(dir_fd, entry->d_name, 0) == 0) ++this_pass;
      }
    }
    removed += this_pass;
    if (this_pass == 0) break;
  }
  return removed;
}

// The matching files of the folder open as `dir_fd`, then its scratch folders with their
// files; async-signal-safe.
int RemoveNamed(int dir_fd, const TemporaryNames& names) {
  int removed = RemoveMatching(dir_fd, &names);
  for (const std::string& folder : names.folders) {
    const int fd =
        ::openat(dir_fd, folder.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) continue;
    removed += RemoveMatching(fd, nullptr);
    ::close(fd);
    if (::unlinkat(dir_fd, folder.c_str(), AT_REMOVEDIR) == 0) ++removed;
  }
  return removed;
}

void WriteMessage() {
  const char* text = g_message.empty() ? "\noccgt: interrupted\n" : g_message.c_str();
  ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

[[noreturn]] void Act(int signal_number) {
  WriteMessage();
  if (g_registered.load()) {
    if (const int fd = ::open(g_names.dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); fd >= 0) {
      RemoveNamed(fd, g_names);
      ::close(fd);
    }
    if (g_names.remove_dir_if_empty) ::rmdir(g_names.dir.c_str());  // fails when not empty
  }
  std::signal(signal_number, SIG_DFL);
  // Inside the handler the signal is blocked until it returns, which Act never does.
  sigset_t unblock;
  sigemptyset(&unblock);
  sigaddset(&unblock, signal_number);
  pthread_sigmask(SIG_UNBLOCK, &unblock, nullptr);
  std::raise(signal_number);
  ::_exit(128 + signal_number);  // not reached: the signal's default action ends the process
}

extern "C" void OnInterrupt(int signal_number) {
  int held = 1;
  if (g_hold.compare_exchange_strong(held, -signal_number)) return;  // acted on at the end
  if (held < 0) return;  // a second signal while held: the first is acted on
  Act(signal_number);
}

}  // namespace

void ExitOnInterrupt(const std::string& advice) {
  g_message = "\noccgt: interrupted; " + advice + "\n";
  std::signal(SIGINT, OnInterrupt);
  std::signal(SIGTERM, OnInterrupt);
}

void RemoveOnInterrupt(const TemporaryNames& names) {
  g_names = names;
  g_registered.store(true);
}

int RemoveTemporaries(const TemporaryNames& names) {
  const int fd = ::open(names.dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return 0;
  const int removed = RemoveNamed(fd, names);
  ::close(fd);
  return removed;
}

HoldInterrupts::HoldInterrupts() { g_hold.store(1); }

HoldInterrupts::~HoldInterrupts() {
  const int state = g_hold.exchange(0);
  if (state < 0) Act(-state);
}

void EndInterrupted(int signal_number, const std::string& detail) {
  if (g_message.empty()) g_message = "occgt: interrupted (" + detail + ")\n";
  Act(signal_number);
}

}  // namespace occgt
