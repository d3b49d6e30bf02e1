#include "services/mapping/lcm/mapper_process.h"

#include <chrono>

#include <lcm/lcm-cpp.hpp>

#include "common/layers.h"
#include "common/log.h"
#include "mapstore/lcm/mapstore_client.h"

namespace cairn::mapping {

std::string MapperLcmUrl(const std::string& flag_value) {
  return runtime::WithReceiveBuffer(runtime::ResolveLcmUrl(flag_value),
                                    runtime::kLargeReceiveBufferBytes);
}

bool RestoreLongTerm(runtime::Node& node, MapperParams* params) {
  const std::string& where = params->long_term_store;
  const auto slash = where.find('/');
  if (slash == std::string::npos) return true;  // Validate() reports the bad name
  mapstore::MapstoreClientOptions options;
  options.total_timeout_s = params->long_term_load_timeout_s;
  mapstore::MapstoreClient client(node.lcm(), "cairn-mapper-" + params->robot, options);
  auto loaded = client.Load(where.substr(0, slash), where.substr(slash + 1), /*version=*/0,
                            /*profile=*/"", {layers::kLongTerm});
  if (loaded.ok()) {
    node.Event("long-term layer restored from %s version %lld", where.c_str(),
               static_cast<long long>(loaded->reply.version));
    params->core.dynamic.long_term_restore = std::move(loaded->layers);
    return true;
  }
  if (loaded.status().code() == common::StatusCode::kNotFound) {
    node.Event("no long-term layer stored as %s yet: it starts as the static map", where.c_str());
    return true;
  }
  CAIRN_LOG_ERROR("cannot restore the long-term layer from %s: %s", where.c_str(),
                  loaded.status().ToString().c_str());
  return false;
}

int ReplayLog(runtime::Node& node, MapperService& service, const std::string& log_path,
              const std::string& output) {
  lcm::LogFile log(log_path, "r");
  if (!log.good()) {
    CAIRN_LOG_ERROR("cannot read log %s", log_path.c_str());
    return 1;
  }
  const auto start = std::chrono::steady_clock::now();
  int64_t events = 0;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    service.HandleLogged(event->channel, event->data, event->datalen);
    ++events;
    if (runtime::ShutdownRequested()) break;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  node.Event("replayed %lld messages, %lld revolutions in %.2f s (%.1f revolutions/s)",
             static_cast<long long>(events), static_cast<long long>(service.revolutions()), seconds,
             seconds > 0 ? service.revolutions() / seconds : 0.0);
  if (!output.empty()) {
    const common::Status status = service.WriteOutputs(output);
    if (!status.ok()) {
      CAIRN_LOG_ERROR("%s", status.ToString().c_str());
      return 1;
    }
    node.Event("maps written to %s", output.c_str());
  }
  return 0;
}

}  // namespace cairn::mapping
