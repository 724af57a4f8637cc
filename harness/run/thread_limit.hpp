#pragma once
#include <memory>

namespace caustics {

// Limits TBB to `threads` workers for its lifetime (0: no limit) and reports the effective count.
class ThreadLimit {
public:
    explicit ThreadLimit(int threads);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;
    static int effective();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace caustics
