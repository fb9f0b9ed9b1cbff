#ifndef DALA_FRONTEND_WORKER_THREAD_H_
#define DALA_FRONTEND_WORKER_THREAD_H_

// One persistent thread running one task at a time, for work split in two halves every frame
// (the frontend detects the right image there while the calling thread detects the left one).
// A thread started per frame would lose its thread_local scratch buffers (DetectHarris keeps
// its images there) and pay their page faults again on every frame.
//
// Usage:
//   WorkerThread worker;
//   worker.Start([&] { right = DetectHarris(frame.right, options); });
//   left = DetectHarris(frame.left, options);
//   worker.Wait();
// Copying gives a new, idle worker (each owner has its own thread). Start and Wait must be
// called from one thread; the thread is started lazily and joined by the destructor.

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace dala {

class WorkerThread {
 public:
  WorkerThread() = default;
  WorkerThread(const WorkerThread&) : WorkerThread() {}
  WorkerThread& operator=(const WorkerThread&) { return *this; }
  ~WorkerThread();

  // Runs `task` on the worker thread and returns at once. CHECK-fails when a task is pending
  // (call Wait first).
  void Start(std::function<void()> task);
  // Blocks until the last started task has finished.
  void Wait();

 private:
  void Loop();

  std::mutex mutex_;
  std::condition_variable cv_;
  std::function<void()> task_;
  bool busy_ = false;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace dala

#endif  // DALA_FRONTEND_WORKER_THREAD_H_
