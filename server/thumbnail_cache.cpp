// ThumbnailCache (server/thumbnail.hpp): an LRU list plus an index into it, bounded by bytes.
#include "server/thumbnail.hpp"

namespace server {

ThumbnailCache::ThumbnailCache(std::size_t byte_cap) { stats_.byte_cap = byte_cap; }

std::shared_ptr<const std::vector<std::uint8_t>> ThumbnailCache::find(const std::string& key) {
  std::lock_guard lock(mutex_);
  const auto it = index_.find(key);
  if (it == index_.end()) {
    ++stats_.misses;
    return nullptr;
  }
  ++stats_.hits;
  lru_.splice(lru_.begin(), lru_, it->second);  // becomes the most recently used
  return it->second->png;
}

void ThumbnailCache::insert(const std::string& key,
                            std::shared_ptr<const std::vector<std::uint8_t>> png) {
  if (!png) return;  // nothing to store
  const std::size_t bytes = png->size() + key.size();
  std::lock_guard lock(mutex_);
  if (bytes > stats_.byte_cap) return;
  if (const auto it = index_.find(key); it != index_.end()) {
    // replace: the newer render of the same key wins
    stats_.bytes -= it->second->bytes;
    it->second->png = std::move(png);
    it->second->bytes = bytes;
    stats_.bytes += bytes;
    lru_.splice(lru_.begin(), lru_, it->second);
  } else {
    lru_.push_front(Entry{key, std::move(png), bytes});
    index_.emplace(key, lru_.begin());
    stats_.bytes += bytes;
    stats_.entries = lru_.size();
  }
  evict_to(stats_.byte_cap);
}

void ThumbnailCache::evict_to(std::size_t cap) {
  // the least recently used entry is at the back; the front one was just stored and fits
  while (stats_.bytes > cap && !lru_.empty()) {
    const Entry& victim = lru_.back();
    stats_.bytes -= victim.bytes;
    index_.erase(victim.key);
    lru_.pop_back();
    ++stats_.evictions;
  }
  stats_.entries = lru_.size();
}

void ThumbnailCache::clear() {
  std::lock_guard lock(mutex_);
  lru_.clear();
  index_.clear();
  stats_.bytes = 0;
  stats_.entries = 0;
}

ThumbnailCacheStats ThumbnailCache::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace server
