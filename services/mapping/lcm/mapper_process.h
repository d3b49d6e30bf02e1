#pragma once

#include <string>

#include "services/mapping/lcm/mapper_service.h"
#include "services/mapping/mapper_config.h"
#include "services/runtime/node.h"

/// @file
/// The steps of the cairn-mapper process around its MapperService: restoring the long-term
/// layer from cairn-mapstore before the service starts, and mapping an lcm-logger file offline.

namespace cairn::mapping {

/// The bus URL of a live mapper (runtime::ResolveLcmUrl of the flag) with a 4 MB receive buffer
/// on udpm: the mapper's socket takes every message on the bus, its own tile bursts included, and
/// with the kernel's default (about 208 KB) a busy host dropped datagrams there, a control request
/// among them. An explicit recv_buf_size is kept; the kernel caps it at net.core.rmem_max.
std::string MapperLcmUrl(const std::string& flag_value);

/// Seed 001's memory across runs: loads the long-term layer last saved to
/// params->long_term_store into params->core.dynamic.long_term_restore. NOT_FOUND (the first
/// run) is fine: the layer starts as the static map. Returns false (after logging why) when the
/// mapper must not start: the store did not answer, or failed.
bool RestoreLongTerm(runtime::Node& node, MapperParams* params);

/// Feeds every message of the lcm-logger file `log_path` to a replay-mode `service`, in log
/// order, then writes the maps under `output` (unless empty). Returns the process exit code.
int ReplayLog(runtime::Node& node, MapperService& service, const std::string& log_path,
              const std::string& output);

}  // namespace cairn::mapping
