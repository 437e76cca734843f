#pragma once
// A disk cache for generated bodies. Generating the default body takes ~7 s (the L0 simplification dominates),
// too long for every start of `strata crowd`, so the first run stores the levels and later runs load them in
// milliseconds. The file lives in $XDG_CACHE_HOME/strata (else ~/.cache/strata), is keyed by a hash of
// everything the body depends on (generator version, options, skeleton), and is written atomically; a missing,
// stale, truncated or corrupt file is ignored and regenerated. STRATA_NO_BODY_CACHE=1 turns the cache off.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "components/skeleton.h"
#include "rig/body_generator.h"

namespace strata {

// Key of a body generated from `skeleton` with `options` by generator `version`.
std::uint64_t body_cache_key(const Skeleton& skeleton, const BodyOptions& options, std::uint32_t version);

// Directory of the cache, or nullopt when none can be used (disabled, no HOME).
std::optional<std::filesystem::path> body_cache_directory();

// Arrays of finite floats derived from a body (centres of rotation, ambient occlusion), cached beside it: an
// 8-byte magic, the key, the item count, then count * floats_per_item floats. Loading gives nullopt for a missing,
// stale (other magic or key), truncated, oversized (> max_items) or non-finite file; saving writes atomically and
// ignores failures (the cache is an optimisation).
std::optional<std::vector<float>> load_float_cache(const std::filesystem::path& file, const char (&magic)[8],
                                                   std::uint64_t key, std::size_t floats_per_item,
                                                   std::uint64_t max_items);
void save_float_cache(const std::filesystem::path& file, const char (&magic)[8], std::uint64_t key,
                      std::size_t floats_per_item, std::span<const float> values);

// Loads the levels stored under `key` in `file`; nullopt when absent or unusable for any reason.
std::optional<BodyLevels> load_body_cache(const std::filesystem::path& file, std::uint64_t key);
// Stores `levels` under `key`; failures are silent (the cache is an optimisation).
void save_body_cache(const std::filesystem::path& file, std::uint64_t key, const BodyLevels& levels);

// The body stored as "<stem>_<key in hex>.bin" in the cache directory, else make()'s, which is then stored there
// (the shipped bodies: rig/body_generator.h default_body, rig/makehuman_body.h makehuman_default_body).
BodyLevels cached_body_levels(std::string_view stem, std::uint64_t key, const std::function<BodyLevels()>& make);

}  // namespace strata
