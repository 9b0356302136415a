// The batch kernels' thread pool: the calling thread works through fixed chunks and up to
// nthreads - 1 persistent helpers join in as they wake up. The caller never waits for a helper
// that has not started: it claims the chunks itself, and at the end waits only for chunks a
// helper has already claimed. So a helper that the OS has descheduled (a loaded 2-core machine:
// an OpenMP team's join barrier waited a full scheduler slice, 8 or 16 ms, for such a thread)
// costs nothing; small and medium calls finish in their own time.
// Between chunks the calling thread polls an interrupt hook (the bindings install one that
// checks for Ctrl-C), at most every kInterruptPollMs; a true answer abandons the remaining chunks.
#pragma once
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include <unistd.h>

namespace bsdfkit {

// Returns true to stop the running batch (e.g. a pending KeyboardInterrupt). Called only on
// the thread that started the batch.
using InterruptHook = bool (*)();
inline std::atomic<InterruptHook> &interrupt_hook() {
    static std::atomic<InterruptHook> hook{nullptr};
    return hook;
}

inline constexpr int kInterruptPollMs = 20;

// Rate-limited view of the hook for one batch.
class InterruptPoll {
public:
    InterruptPoll() : hook_(interrupt_hook().load()), last_(std::chrono::steady_clock::now()) {}
    bool operator()() {
        if (!hook_) return false;
        auto now = std::chrono::steady_clock::now();
        if (now - last_ < std::chrono::milliseconds(kInterruptPollMs)) return false;
        last_ = now;
        return stopped_ = stopped_ || hook_();
    }
    bool stopped() const { return stopped_; }

private:
    InterruptHook hook_;
    std::chrono::steady_clock::time_point last_;
    bool stopped_ = false;
};

class ChunkPool {
public:
    // One pool per process, never destroyed (its helpers end with the process).
    static ChunkPool &instance() {
        static ChunkPool *p = new ChunkPool;
        return *p;
    }

    // body(c) for every c in [0, nchunks) on the caller plus up to nthreads - 1 helpers; the
    // caller polls `poll` after each of its chunks. Returns false if the poll stopped the batch.
    template <typename Body> bool run(int64_t nchunks, int nthreads, const Body &body, InterruptPoll &poll) {
        // Serial when one thread suffices, when another batch holds the pool (a concurrent call),
        // or in a forked child (whose copy of the pool has no helper threads).
        if (nthreads <= 1 || nchunks <= 1 || getpid() != pid_ || busy_.exchange(true)) {
            for (int64_t c = 0; c < nchunks; ++c) {
                body(c);
                if (poll()) return false;
            }
            return true;
        }
        int helpers = int(std::min<int64_t>(nthreads - 1, nchunks - 1));
        {
            std::lock_guard<std::mutex> lk(mu_);
            while (int(workers_.size()) < helpers) workers_.emplace_back([this] { work(); });
            call_ = [](const void *ctx, int64_t c) { (*static_cast<const Body *>(ctx))(c); };
            ctx_ = &body;
            nchunks_ = nchunks;
            next_.store(0);
            ++gen_;
            wanted_ = helpers;
        }
        cv_.notify_all();
        bool stopped = false;
        for (int64_t c; (c = next_.fetch_add(1)) < nchunks;) {
            body(c);
            if (poll()) {
                next_.store(nchunks); // helpers finish their current chunk and leave
                stopped = true;
                break;
            }
        }
        {
            std::unique_lock<std::mutex> lk(mu_);
            call_ = nullptr; // helpers that have not joined yet never will
            wanted_ = 0;
            done_.wait(lk, [this] { return inside_ == 0; });
        }
        busy_.store(false);
        return !stopped;
    }

private:
    ChunkPool() : pid_(getpid()) {}

    void work() {
        uint64_t seen = 0;
        std::unique_lock<std::mutex> lk(mu_);
        for (;;) {
            cv_.wait(lk, [&] { return call_ != nullptr && wanted_ > 0 && gen_ != seen; });
            seen = gen_;
            --wanted_;
            ++inside_;
            void (*call)(const void *, int64_t) = call_;
            const void *ctx = ctx_;
            int64_t n = nchunks_;
            lk.unlock();
            for (int64_t c; (c = next_.fetch_add(1)) < n;) call(ctx, c);
            lk.lock();
            if (--inside_ == 0) done_.notify_all();
        }
    }

    const pid_t pid_;
    std::mutex mu_;
    std::condition_variable cv_, done_;
    std::vector<std::thread> workers_;
    std::atomic<bool> busy_{false};
    std::atomic<int64_t> next_{0};
    // The current batch (guarded by mu_).
    void (*call_)(const void *, int64_t) = nullptr;
    const void *ctx_ = nullptr;
    int64_t nchunks_ = 0;
    uint64_t gen_ = 0;
    int wanted_ = 0, inside_ = 0;
};

} // namespace bsdfkit
