// The pipeline's long-lived CPU thread: tasks run in order on one thread, results and exceptions
// come back through the futures, and destruction finishes what was submitted.
#include "shared/worker_thread.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace ag {
namespace {

TEST(WorkerThread, RunsTasksInOrderOnOneThread) {
    std::vector<int> order;
    std::vector<std::future<std::thread::id>> ids;
    {
        WorkerThread worker;
        for (int i = 0; i < 20; ++i)
            ids.push_back(worker.submit([&order, i] {
                order.push_back(i);
                return std::this_thread::get_id();
            }));
        const std::thread::id first = ids[0].get();
        EXPECT_NE(first, std::this_thread::get_id());
        for (size_t i = 1; i < ids.size(); ++i) EXPECT_EQ(ids[i].get(), first);
    }
    ASSERT_EQ(order.size(), 20u);
    for (int i = 0; i < 20; ++i) EXPECT_EQ(order[size_t(i)], i);
}

TEST(WorkerThread, ResultsAndExceptionsComeThroughTheFuture) {
    WorkerThread worker;
    EXPECT_EQ(worker.submit([] { return 42; }).get(), 42);
    std::future<int> failing = worker.submit([]() -> int { throw std::runtime_error("no"); });
    EXPECT_THROW(failing.get(), std::runtime_error);
    EXPECT_EQ(worker.submit([] { return 7; }).get(), 7);  // still running
}

TEST(WorkerThread, DestructionFinishesSubmittedTasks) {
    std::atomic<int> done{0};
    {
        WorkerThread worker;
        for (int i = 0; i < 50; ++i) (void)worker.submit([&done] { ++done; });
    }
    EXPECT_EQ(done.load(), 50);
}

}  // namespace
}  // namespace ag
