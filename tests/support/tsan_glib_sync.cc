// ThreadSanitizer builds only: cmake/CairnAddTest.cmake compiles this file into every test when
// CAIRN_SANITIZE names "thread".
//
// liblcm's memq provider (the unit tests' in-process bus) hands each message from the
// publishing thread to the dispatching one through a queue guarded by glib's GMutex and GCond.
// glib implements both with raw futexes, which ThreadSanitizer cannot see, so every message
// looked like memory shared without synchronisation: the buffer liblcm allocates and fills on
// the worker that publishes, then decodes and frees on the thread that handles. These
// definitions interpose glib's lock, unlock and wait as liblcm calls them (through its PLT; the
// executable's definitions come first) and tell ThreadSanitizer what they do: an unlock releases
// what the thread did before, a lock acquires what the last holder released. Nothing is
// suppressed: a race in cairn's handlers and workers is still a race.

#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>

extern "C" {
void __tsan_acquire(void* addr);
void __tsan_release(void* addr);
}

namespace {

template <typename Fn>
Fn Next(const char* name) {
  void* f = dlsym(RTLD_NEXT, name);
  if (f == nullptr) {
    std::fprintf(stderr, "tsan_glib_sync: glib's %s not found\n", name);
    std::abort();
  }
  return reinterpret_cast<Fn>(f);
}

using MutexFn = void (*)(void*);
using CondWaitFn = void (*)(void*, void*);

}  // namespace

extern "C" {

void g_mutex_lock(void* mutex) {
  static const MutexFn next = Next<MutexFn>("g_mutex_lock");
  next(mutex);
  __tsan_acquire(mutex);
}

void g_mutex_unlock(void* mutex) {
  static const MutexFn next = Next<MutexFn>("g_mutex_unlock");
  __tsan_release(mutex);
  next(mutex);
}

void g_cond_wait(void* cond, void* mutex) {
  static const CondWaitFn next = Next<CondWaitFn>("g_cond_wait");
  __tsan_release(mutex);
  next(cond, mutex);
  __tsan_acquire(mutex);
}

}  // extern "C"
