// A large read-only resource shared by models: a lookup table (Filament's DFG), a measured BRDF.
//
// The pattern (core/bxdf.h): a model that needs such a table is a trivially copyable `Kernel`
// (its parameters and plain pointers into the table) plus a SharedTable<T> that keeps the table
// alive. The batch kernels copy only the Kernel per chunk (its values then stay in registers);
// the table is never copied: every model built from it, the renderer's materials and the Python
// handle share one immutable instance. The table enters a model through its Params as a field of
// type SharedTable<T>, like any other parameter (the bindings convert it by type, core/bxdf.h).
//
// The content digest identifies the table's values (not its address): Python compares and hashes
// models holding a table by (path or size, digest) instead of by the values. A table type T
// provides it by an overload `uint64_t content_digest(const T &)` found by argument-dependent
// lookup; digest_bytes() below is the building block.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <utility>

namespace bsdfkit {

// FNV-1a (64 bit) over a byte range, continuing from `h` (chain calls to digest several ranges).
inline uint64_t digest_bytes(const void *data, size_t n, uint64_t h = 0xcbf29ce484222325ull) {
    const unsigned char *p = static_cast<const unsigned char *>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
    return h;
}

template <typename T> class SharedTable {
public:
    using value_type = T;

    SharedTable() = default;  // empty: a model's make() must not be called with it (bindings check)
    explicit SharedTable(std::shared_ptr<const T> p) : ptr_(std::move(p)), digest_(ptr_ ? content_digest(*ptr_) : 0) {}

    template <typename... Args> static SharedTable make(Args &&...args) {
        return SharedTable(std::make_shared<const T>(std::forward<Args>(args)...));
    }

    explicit operator bool() const { return bool(ptr_); }
    const T &operator*() const { return *ptr_; }
    const T *operator->() const { return ptr_.get(); }
    const T *get() const { return ptr_.get(); }
    const std::shared_ptr<const T> &shared() const { return ptr_; }
    uint64_t digest() const { return digest_; }

    // Same values (the digest, then the address as a shortcut; a digest collision is not handled).
    friend bool operator==(const SharedTable &a, const SharedTable &b) {
        return a.ptr_ == b.ptr_ || (a.ptr_ && b.ptr_ && a.digest_ == b.digest_);
    }
    friend bool operator!=(const SharedTable &a, const SharedTable &b) { return !(a == b); }

private:
    std::shared_ptr<const T> ptr_;
    uint64_t digest_ = 0;
};

template <typename T> struct is_shared_table : std::false_type {};
template <typename T> struct is_shared_table<SharedTable<T>> : std::true_type {};

} // namespace bsdfkit
