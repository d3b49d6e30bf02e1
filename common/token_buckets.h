#pragma once

#include <cstddef>
#include <cstdint>
#include <list>
#include <string>
#include <unordered_map>

/// @file
/// Token buckets that bound how much work requests from the bus may ask for (resend requests):
/// one bucket per requester, and one over every requester together, so neither one noisy peer
/// nor many names from one hostile peer make a process send without limit. Time is passed in.

namespace cairn::common {

struct TokenBucketsParams {
  double rate_per_s{1000.0};         ///< tokens a requester gains a second
  double burst{2000.0};              ///< most tokens a requester holds
  double total_rate_per_s{3000.0};   ///< tokens every requester together gains a second
  double total_burst{6000.0};
  size_t max_requesters{256};        ///< buckets kept; the least recently used goes

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

class TokenBuckets {
 public:
  explicit TokenBuckets(TokenBucketsParams params);

  /// Takes `tokens` from the requester's bucket and the total one when both hold them (true);
  /// otherwise takes nothing (false). `now_s`: a monotonic clock.
  bool Allow(const std::string& requester, double tokens, double now_s);
  /// Requests refused so far.
  int64_t refused() const { return refused_; }

 private:
  struct Bucket {
    double tokens{0.0};
    double last_s{0.0};
    std::list<std::string>::iterator lru;
  };
  static void Refill(Bucket* b, double rate_per_s, double burst, double now_s);

  TokenBucketsParams params_;
  Bucket total_;
  std::unordered_map<std::string, Bucket> buckets_;
  std::list<std::string> lru_;  // most recently used first
  int64_t refused_{0};
};

}  // namespace cairn::common
