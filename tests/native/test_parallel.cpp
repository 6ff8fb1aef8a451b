// parallel_for (native/src/parallel.h), which readback's copies and the
// Cryptomatte ranking run on: every index once, the first exception
// rethrown after every thread has ended, nothing for a count of zero.
#include "parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

using deferred::parallel_for;

TEST(ParallelFor, EveryIndexExactlyOnce) {
    for (std::size_t count : {0u, 1u, 2u, 3u, 17u, 1000u}) {
        std::vector<std::atomic<int>> seen(count);
        parallel_for(count, [&](std::size_t i) { seen[i].fetch_add(1); });
        for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(seen[i].load(), 1) << "count " << count << " index " << i;
    }
}

TEST(ParallelFor, AnExceptionComesBackAfterTheOtherIndicesRan) {
    std::atomic<int> ran{0};
    EXPECT_THROW(parallel_for(64, [&](std::size_t i) {
                     ran.fetch_add(1);
                     if (i == 5) throw std::runtime_error("index 5");
                 }),
                 std::runtime_error);
    EXPECT_EQ(ran.load(), 64);  // the others were not abandoned half-way
}
