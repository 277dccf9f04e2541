// One long-lived thread that runs submitted tasks one at a time, in order, beside the caller: for
// work started every frame. A thread started per frame (std::async) costs a thread start each time
// and leaves per-thread state behind in libraries that keep it until exit (Embree's BVH builder
// keeps an allocator for every thread that ever committed a scene: some KB per frame).
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>

namespace ag {

class WorkerThread {
public:
    WorkerThread();
    ~WorkerThread();  // finishes the tasks already submitted
    WorkerThread(const WorkerThread&) = delete;
    WorkerThread& operator=(const WorkerThread&) = delete;

    // Runs `task` on the worker after the tasks before it; its result or exception comes through
    // the future.
    template <typename F>
    auto submit(F task) -> std::future<decltype(task())> {
        using Result = decltype(task());
        auto packaged = std::make_shared<std::packaged_task<Result()>>(std::move(task));
        std::future<Result> result = packaged->get_future();
        push([packaged] { (*packaged)(); });
        return result;
    }

private:
    void push(std::function<void()> task);
    void loop();

    std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<std::function<void()>> tasks_;
    bool stop_ = false;
    std::thread thread_;  // last: started once the members above exist
};

}  // namespace ag
