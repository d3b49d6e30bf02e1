#include "common/token_buckets.h"

#include <algorithm>

#include "common/check.h"

namespace cairn::common {

void TokenBucketsParams::Validate() const {
  CAIRN_THROW_UNLESS(rate_per_s > 0 && burst > 0, "the rate and burst must be positive");
  CAIRN_THROW_UNLESS(total_rate_per_s > 0 && total_burst > 0,
                     "the total rate and burst must be positive");
  CAIRN_THROW_UNLESS(max_requesters >= 1, "max_requesters must be >= 1");
}

TokenBuckets::TokenBuckets(TokenBucketsParams params) : params_(params) {
  params_.Validate();
  total_.tokens = params_.total_burst;
  total_.last_s = -1.0;
}

void TokenBuckets::Refill(Bucket* b, double rate_per_s, double burst, double now_s) {
  if (b->last_s >= 0.0 && now_s > b->last_s) {
    b->tokens = std::min(burst, b->tokens + (now_s - b->last_s) * rate_per_s);
  }
  b->last_s = std::max(b->last_s, now_s);
}

bool TokenBuckets::Allow(const std::string& requester, double tokens, double now_s) {
  auto it = buckets_.find(requester);
  if (it == buckets_.end()) {
    if (buckets_.size() >= params_.max_requesters) {
      buckets_.erase(lru_.back());
      lru_.pop_back();
    }
    lru_.push_front(requester);
    Bucket fresh;
    fresh.tokens = params_.burst;
    fresh.last_s = now_s;
    fresh.lru = lru_.begin();
    it = buckets_.emplace(requester, fresh).first;
  } else {
    lru_.splice(lru_.begin(), lru_, it->second.lru);
  }
  Bucket& own = it->second;
  Refill(&own, params_.rate_per_s, params_.burst, now_s);
  Refill(&total_, params_.total_rate_per_s, params_.total_burst, now_s);
  if (own.tokens < tokens || total_.tokens < tokens) {
    ++refused_;
    return false;
  }
  own.tokens -= tokens;
  total_.tokens -= tokens;
  return true;
}

}  // namespace cairn::common
