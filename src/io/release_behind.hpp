// Releasing a shared file mapping's pages behind its readers (the session.csv loader).
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <mutex>
#include <utility>
#include <vector>

namespace metro::internal {

// The session.csv loader maps the file once for two readers: the parser, whose blocks
// finish in any order, and the SHA-256 hasher, which goes front to back at its own pace.
// A byte is behind the parser once every block up to it is parsed, and behind the hasher
// once hashed. Pages (`release(begin, end)`) go
//  - once both readers are past them (each page is then read once, by both), and
//  - when the hasher trails the parser (a CPU without SHA extensions), once the parser is
//    past them and they lie more than `max_gap_bytes` ahead of the hasher: the hasher maps
//    them again when it gets there, and they go again once it is past.
// So behind the parser, where the tag columns grow, at most max_gap_bytes of the file stay
// mapped for a slow hasher, instead of everything it has not hashed yet. A hasher ahead of
// the parser releases nothing ahead of it: the parser's first pass has mapped those pages
// already, and they go as the parser passes them. Releasing a page a reader still needs
// costs it a fault (the page comes back from the page cache), never a wrong byte.
// Thread-safe.
class ReleaseBehind {
 public:
  // `release` drops [begin, end) (MappedFile::ReleaseBelow); without a hasher (`hashing`
  // false) the parser alone holds pages.
  ReleaseBehind(std::function<void(size_t, size_t)> release, bool hashing, size_t max_gap_bytes)
      : release_(std::move(release)), hashing_(hashing), max_gap_bytes_(max_gap_bytes) {}

  // Starts a parse of blocks [begins[i], ends[i]) covering the file from begins[0] (the
  // bytes before it, the header, are read before any block) to the end. A new pass (the
  // general loader after the clean path gave up) reads the pages again, so the release
  // starts again from the first block.
  void StartPass(const std::vector<size_t>& begins, const std::vector<size_t>& ends) {
    std::unique_lock<std::mutex> lock(mutex_);
    ends_ = ends;
    done_.assign(ends.size(), false);
    next_ = 0;
    parsed_ = begins.empty() ? 0 : begins.front();
    released_ = 0;
    released_ahead_ = 0;
    ReleaseBehindBoth(&lock);
  }

  // Block i of the current pass is parsed (or will not be read: a strict load that stopped).
  void BlockDone(size_t i) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (i >= done_.size()) return;
    done_[i] = true;
    while (next_ < done_.size() && done_[next_]) parsed_ = ends_[next_++];
    ReleaseBehindBoth(&lock);
  }

  // The hasher has hashed [0, bytes).
  void Hashed(size_t bytes) {
    std::unique_lock<std::mutex> lock(mutex_);
    hashed_ = std::max(hashed_, bytes);
    ReleaseBehindBoth(&lock);
  }

 private:
  void ReleaseBehindBoth(std::unique_lock<std::mutex>* lock) {
    const size_t trailing = hashing_ ? std::min(parsed_, hashed_) : parsed_;
    std::pair<size_t, size_t> both{0, 0};  // Behind both readers.
    if (trailing > released_) {
      both = {released_, trailing};
      released_ = trailing;
    }
    std::pair<size_t, size_t> ahead{0, 0};  // Behind the parser, far ahead of the hasher.
    if (hashing_ && parsed_ > hashed_) {
      const size_t far = hashed_ + std::min(max_gap_bytes_, parsed_ - hashed_);
      const size_t from = std::max(far, released_ahead_);
      if (parsed_ > from) {
        ahead = {from, parsed_};
        released_ahead_ = parsed_;
      }
    }
    lock->unlock();  // madvise outside the lock; each range is claimed by one caller.
    if (both.second > both.first) release_(both.first, both.second);
    if (ahead.second > ahead.first) release_(ahead.first, ahead.second);
  }

  std::mutex mutex_;
  std::function<void(size_t, size_t)> release_;
  bool hashing_;
  size_t max_gap_bytes_;
  std::vector<size_t> ends_;
  std::vector<bool> done_;
  size_t next_ = 0;            // First block not yet done.
  size_t parsed_ = 0;          // [0, parsed_) is behind the parser.
  size_t hashed_ = 0;          // [0, hashed_) is behind the hasher.
  size_t released_ = 0;        // [0, released_) is released (in this pass).
  size_t released_ahead_ = 0;  // Far ahead of the hasher, released up to here.
};

}  // namespace metro::internal
