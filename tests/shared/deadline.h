// For tests whose failure mode is a hang: runs `body` on its own thread and, if it has not
// returned within the deadline, fails the test and ends the test binary (a hung thread cannot be
// stopped, and waiting for it would hang the test run).
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <future>
#include <memory>
#include <thread>

namespace ag::test {

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
    if (finished.wait_for(deadline) != std::future_status::ready) {
        ADD_FAILURE() << "still running after " << deadline.count() << " s (hung?)";
        std::_Exit(1);
    }
    finished.get();
}

}  // namespace ag::test
