// Large output blocks kept for reuse (sample's seven outputs live in one block, bind_model.h).
//
// Why: glibc serves an allocation above its mmap threshold (dynamic, 32 MiB at most on 64-bit)
// with fresh pages and unmaps them on free, so a 35 MiB float32 sample block at N = 1e6 was
// page-faulted again on every call: 6-12 ms of faults for a 3 ms kernel (bench/RESULTS.md of
// commit b815202, now tools/perf/results/: plain sample 164 M/s vs 303 M/s with preallocated
// outputs). A block returned here keeps its pages; the next call of a similar size gets them warm.
//
// Bounds: blocks below kMinBytes are not cached (malloc reuses those itself); at most kMaxKept
// blocks and kMaxKeptBytes are held while unused (the most recently returned win). Everything
// runs with the GIL held (array creation and capsule destructors), the mutex only guards
// against a caller without it.
#pragma once
#include <pybind11/pybind11.h>

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <new>
#include <vector>

namespace py = pybind11;

namespace bsdfkit::py_bind {

class BlockCache {
  public:
    static constexpr size_t kMinBytes = size_t(1) << 20;
    static constexpr size_t kMaxKept = 2;
    static constexpr size_t kMaxKeptBytes = size_t(512) << 20;
    static constexpr size_t kGranule = size_t(2) << 20;  // huge-page size: capacities and alignment

    struct Block {
        void *ptr;
        size_t capacity;
    };

    // Leaked on purpose: capsules may be destroyed during interpreter shutdown, after static
    // destructors would have run.
    static BlockCache &instance() {
        static BlockCache *c = new BlockCache();
        return *c;
    }

    // A block of at least `bytes`: the smallest kept one that is not more than twice too large,
    // else a new one (2 MiB aligned, huge pages requested, untouched).
    Block get(size_t bytes) {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            size_t best = kept_.size();
            for (size_t i = 0; i < kept_.size(); ++i)
                if (kept_[i].capacity >= bytes && kept_[i].capacity <= 2 * bytes + kGranule &&
                    (best == kept_.size() || kept_[i].capacity < kept_[best].capacity))
                    best = i;
            if (best != kept_.size()) {
                Block b = kept_[best];
                kept_.erase(kept_.begin() + std::ptrdiff_t(best));
                kept_bytes_ -= b.capacity;
                return b;
            }
        }
        size_t cap = (bytes + kGranule - 1) / kGranule * kGranule;
        void *p = nullptr;
        if (posix_memalign(&p, kGranule, cap) != 0) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
        madvise(p, cap, MADV_HUGEPAGE);  // a hint; failure is harmless
#endif
        return {p, cap};
    }

    // Takes a block back; frees the oldest kept ones beyond the bounds.
    void put(Block b) {
        std::vector<void *> drop;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            kept_.push_back(b);
            kept_bytes_ += b.capacity;
            while (!kept_.empty() && (kept_.size() > kMaxKept || kept_bytes_ > kMaxKeptBytes)) {
                drop.push_back(kept_.front().ptr);
                kept_bytes_ -= kept_.front().capacity;
                kept_.erase(kept_.begin());
            }
        }
        for (void *p : drop) std::free(p);
    }

    // Frees every kept block (bsdfkit.threads.release_memory); returns the bytes released.
    size_t clear() {
        std::vector<Block> all;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            all.swap(kept_);
            kept_bytes_ = 0;
        }
        size_t n = 0;
        for (const Block &b : all) {
            n += b.capacity;
            std::free(b.ptr);
        }
        return n;
    }

    size_t kept_bytes() {
        std::lock_guard<std::mutex> lock(mutex_);
        return kept_bytes_;
    }

  private:
    std::mutex mutex_;
    std::vector<Block> kept_;
    size_t kept_bytes_ = 0;
};

// A block of at least `bytes` owned by a capsule (numpy arrays made with it as their base keep
// it alive); the capsule's destructor returns it to the cache.
inline py::capsule cached_block(size_t bytes, void **data) {
    auto *b = new BlockCache::Block(BlockCache::instance().get(bytes));
    *data = b->ptr;
    return py::capsule(b, "bsdfkit.block", [](void *p) {
        auto *blk = static_cast<BlockCache::Block *>(p);
        BlockCache::instance().put(*blk);
        delete blk;
    });
}

}  // namespace bsdfkit::py_bind
