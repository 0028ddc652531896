// Clang thread-safety annotations (https://clang.llvm.org/docs/ThreadSafetyAnalysis.html) and a
// mutex that carries them. Under clang with -Wthread-safety the compiler checks that data marked
// SLSLAM_GUARDED_BY(mu) is touched only with `mu` held and that functions marked
// SLSLAM_REQUIRES(mu) are called only with it held; scripts/thread_safety.sh runs that check over
// the core in CI. Under other compilers the macros expand to nothing and Mutex is a std::mutex.
#pragma once

#include <mutex>

#if defined(__clang__)
#define SLSLAM_THREAD_ANNOTATION(x) __attribute__((x))
#else
#define SLSLAM_THREAD_ANNOTATION(x)
#endif

#define SLSLAM_CAPABILITY(x) SLSLAM_THREAD_ANNOTATION(capability(x))
#define SLSLAM_SCOPED_CAPABILITY SLSLAM_THREAD_ANNOTATION(scoped_lockable)
#define SLSLAM_GUARDED_BY(x) SLSLAM_THREAD_ANNOTATION(guarded_by(x))
#define SLSLAM_REQUIRES(...) SLSLAM_THREAD_ANNOTATION(requires_capability(__VA_ARGS__))
#define SLSLAM_ACQUIRE(...) SLSLAM_THREAD_ANNOTATION(acquire_capability(__VA_ARGS__))
#define SLSLAM_RELEASE(...) SLSLAM_THREAD_ANNOTATION(release_capability(__VA_ARGS__))
#define SLSLAM_TRY_ACQUIRE(...) SLSLAM_THREAD_ANNOTATION(try_acquire_capability(__VA_ARGS__))
#define SLSLAM_EXCLUDES(...) SLSLAM_THREAD_ANNOTATION(locks_excluded(__VA_ARGS__))
#define SLSLAM_RETURN_CAPABILITY(x) SLSLAM_THREAD_ANNOTATION(lock_returned(x))
#define SLSLAM_ASSERT_CAPABILITY(x) SLSLAM_THREAD_ANNOTATION(assert_capability(x))

namespace slslam {

// A std::mutex the analysis knows as a capability. Use it with MutexLock (scoped), or with
// std::scoped_lock / std::unique_lock where the analysis cannot follow (then tell it with
// AssertHeld).
class SLSLAM_CAPABILITY("mutex") Mutex {
 public:
  void lock() SLSLAM_ACQUIRE() { mutex_.lock(); }
  void unlock() SLSLAM_RELEASE() { mutex_.unlock(); }
  bool try_lock() SLSLAM_TRY_ACQUIRE(true) { return mutex_.try_lock(); }
  // Tells the analysis that the calling thread holds this mutex (taken by a construct it cannot
  // follow, such as std::scoped_lock over several mutexes). Checks nothing at run time.
  void AssertHeld() const SLSLAM_ASSERT_CAPABILITY(this) {}

 private:
  std::mutex mutex_;
};

// Holds a Mutex for its scope (std::lock_guard with the annotations).
class SLSLAM_SCOPED_CAPABILITY MutexLock {
 public:
  explicit MutexLock(Mutex& mutex) SLSLAM_ACQUIRE(mutex) : mutex_(mutex) { mutex_.lock(); }
  ~MutexLock() SLSLAM_RELEASE() { mutex_.unlock(); }
  MutexLock(const MutexLock&) = delete;
  MutexLock& operator=(const MutexLock&) = delete;

 private:
  Mutex& mutex_;
};

}  // namespace slslam
