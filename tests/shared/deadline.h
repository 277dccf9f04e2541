// Hang guards for tests whose failure mode is a hang. They count only time the process could run:
// on the shared development machine tools stop other sessions' processes (SIGSTOP) while they
// time their own, and a test stopped for minutes must not take that for a hang. A wait returns
// at least every kSlice and counts at most 2 × kSlice of it.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <future>
#include <memory>
#include <mutex>
#include <thread>

namespace ag::test {

inline constexpr std::chrono::milliseconds kSlice{100};

// Every limit below is multiplied by this: 10 in the sanitizers' build, which runs the same work
// 3-10 times slower (tests/CMakeLists.txt, AG_TEST_TIME_SCALE).
#ifndef AG_TEST_TIME_SCALE
#define AG_TEST_TIME_SCALE 1
#endif
inline constexpr int kTimeScale = AG_TEST_TIME_SCALE;

// Counts the time the process could run, from the calls to `tick()`.
class RunningTime {
public:
    // Adds the time since the last tick (at most 2 × kSlice); returns the total.
    std::chrono::steady_clock::duration tick() {
        const std::chrono::steady_clock::time_point now = std::chrono::steady_clock::now();
        counted_ += std::min<std::chrono::steady_clock::duration>(now - last_, 2 * kSlice);
        last_ = now;
        return counted_;
    }

private:
    std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
    std::chrono::steady_clock::duration counted_{0};
};

// Waits on `cv` (with `lock` held) until `ready()` holds or `limit` of running time has passed;
// returns ready().
template <class Ready>
bool wait_running(std::condition_variable& cv, std::unique_lock<std::mutex>& lock,
                  std::chrono::seconds limit, Ready ready) {
    RunningTime time;
    while (!ready()) {
        if (time.tick() >= limit * kTimeScale) return false;
        cv.wait_for(lock, kSlice, ready);
    }
    return true;
}

// Runs `body` on its own thread and, if it has not returned within `deadline` of running time,
// fails the test and ends the test binary (a hung thread cannot be stopped, and waiting for it
// would hang the test run).
template <class Body>
void within_deadline(std::chrono::seconds deadline, Body body) {
    auto done = std::make_shared<std::promise<void>>();
    std::future<void> finished = done->get_future();
    std::thread([done, body]() mutable {
        try {
            body();
            done->set_value();
        } catch (...) {
            done->set_exception(std::current_exception());
        }
    }).detach();
    RunningTime time;
    while (finished.wait_for(kSlice) != std::future_status::ready) {
        if (time.tick() >= deadline * kTimeScale) {
            ADD_FAILURE() << "still running after " << deadline.count() * kTimeScale
                          << " s (hung?)";
            std::_Exit(1);
        }
    }
    finished.get();
}

}  // namespace ag::test
