// A fixed pool of worker threads and a parallel for. Work items write to their own slots and the
// caller merges in index order, so results never depend on the thread count.
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace ag {

class ThreadPool {
public:
    // threads <= 0: one per hardware thread (at least 2, so work never runs on the caller's thread
    // alone even on a single core).
    explicit ThreadPool(int threads = 0);
    ~ThreadPool();
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    int size() const { return int(workers_.size()); }

    // Runs body(i) for i in [0, count) on the workers, in chunks; returns when all are done.
    // The calling thread only waits. If bodies throw, no further chunks start and the exception
    // of the lowest index that threw is rethrown: the one a serial loop would throw, on any
    // thread count and interleaving (where whether body(i) throws depends on i alone).
    void parallel_for(size_t count, const std::function<void(size_t)>& body, size_t chunk = 1);

private:
    void worker_loop();

    std::vector<std::thread> workers_;
    std::mutex mutex_;
    std::condition_variable wake_, done_;
    const std::function<void(size_t)>* body_ = nullptr;
    size_t count_ = 0, next_ = 0, chunk_ = 1, active_ = 0;
    uint64_t generation_ = 0;
    bool stop_ = false;
    std::exception_ptr error_;
    size_t error_index_ = 0;  // the index error_ came from
};

}  // namespace ag
