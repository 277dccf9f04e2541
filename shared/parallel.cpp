#include "shared/parallel.h"

#include <algorithm>

namespace ag {

ThreadPool::ThreadPool(int threads) {
    if (threads <= 0) threads = std::max(2, int(std::thread::hardware_concurrency()));
    for (int i = 0; i < threads; ++i) workers_.emplace_back([this] { worker_loop(); });
}

ThreadPool::~ThreadPool() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
}

void ThreadPool::parallel_for(size_t count, const std::function<void(size_t)>& body, size_t chunk) {
    if (count == 0) return;
    std::unique_lock<std::mutex> lock(mutex_);
    body_ = &body;
    count_ = count;
    next_ = 0;
    chunk_ = std::max<size_t>(1, chunk);
    active_ = workers_.size();
    error_ = nullptr;
    error_index_ = 0;
    ++generation_;
    wake_.notify_all();
    done_.wait(lock, [this] { return active_ == 0; });
    body_ = nullptr;
    if (error_) std::rethrow_exception(error_);
}

void ThreadPool::worker_loop() {
    uint64_t seen = 0;
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
        while (next_ < count_) {
            const size_t begin = next_, end = std::min(count_, next_ + chunk_);
            next_ = end;
            lock.unlock();
            size_t i = begin;
            try {
                for (; i < end; ++i) (*body_)(i);
            } catch (...) {
                // Chunks are handed out in index order, so every index below i is in a chunk
                // already handed out and runs to its end: keeping the lowest index's exception
                // rethrows what a serial loop would, whichever thread threw first.
                lock.lock();
                if (!error_ || i < error_index_) {
                    error_ = std::current_exception();
                    error_index_ = i;
                }
                next_ = count_;
                lock.unlock();
            }
            lock.lock();
        }
        if (--active_ == 0) done_.notify_all();
    }
}

}  // namespace ag
