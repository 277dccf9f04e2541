#include "shared/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <string>

#include "tests/shared/deadline.h"

namespace ag {
namespace {

std::string thrown_by(ThreadPool& pool, size_t count, const std::function<void(size_t)>& body) {
    try {
        pool.parallel_for(count, body);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "nothing thrown";
}

}  // namespace

// Two bodies throw, the higher index first (index 7 waits until index 300 has thrown): the pool
// rethrows index 7's exception, as a serial loop would. Before, it rethrew whichever exception the
// pool caught first: 300 in 52 of 100 such runs of main's pool (the two threads race for its lock
// after 300 has thrown), so this test failed about every other run there.
TEST(ThreadPool, TheLowestThrowingIndexIsRethrownWhicheverThreadThrewFirst) {
    for (const int threads : {2, 4}) {
        ThreadPool pool(threads);
        std::mutex mutex;
        std::condition_variable thrown;
        bool high_thrown = false;
        const std::string what = thrown_by(pool, 1000, [&](size_t i) {
            if (i == 300) {
                {
                    std::lock_guard<std::mutex> lock(mutex);
                    high_thrown = true;
                }
                thrown.notify_all();
                throw std::runtime_error("300");
            }
            if (i == 7) {
                std::unique_lock<std::mutex> lock(mutex);
                EXPECT_TRUE(test::wait_running(thrown, lock, std::chrono::seconds(20),
                                               [&] { return high_thrown; }));
                throw std::runtime_error("7");
            }
        });
        EXPECT_EQ(what, "7") << threads << " threads";
    }
}

// Many throwing indices, many chunkings and thread counts: always the lowest one's exception.
TEST(ThreadPool, TheRethrownExceptionDoesNotDependOnTheThreadCount) {
    for (const int threads : {1, 2, 3, 8})
        for (const size_t chunk : {1, 5, 64}) {
            ThreadPool pool(threads);
            std::string what;
            try {
                pool.parallel_for(
                    5000,
                    [&](size_t i) {
                        if (i % 997 == 411) throw std::runtime_error(std::to_string(i));
                    },
                    chunk);
            } catch (const std::runtime_error& e) {
                what = e.what();
            }
            EXPECT_EQ(what, "411") << threads << " threads, chunk " << chunk;
            // The pool is usable afterwards.
            std::atomic<size_t> sum{0};
            pool.parallel_for(100, [&](size_t i) { sum.fetch_add(i); });
            EXPECT_EQ(sum.load(), size_t(4950));
        }
}

}  // namespace ag
