#include "mapstore/map_transfer.h"

#include <filesystem>

#include "mapstore/names.h"

namespace cairn::mapstore {

namespace fs = std::filesystem;
using common::Result;
using common::Status;

namespace {

std::string JoinNames(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  return list;
}

// The importer of an import: the one named, else the one of the file's extension.
Result<const io::ImportFormat*> ImporterOf(const ImportOptions& options,
                                           const io::FormatRegistry& formats) {
  if (!options.format.empty()) {
    const io::ImportFormat* format = formats.FindImporter(options.format);
    if (format == nullptr) {
      return common::InvalidArgumentError("unknown import format '" + options.format + "' (" +
                                          JoinNames(formats.ImportNames()) + ")");
    }
    return format;
  }
  const io::ImportFormat* format = formats.ImporterForPath(options.path);
  if (format != nullptr) return format;
  std::vector<std::string> known;
  for (const auto& [name, f] : formats.importers()) {
    std::string exts;
    for (const std::string& e : f.extensions) exts += (exts.empty() ? "" : "/") + e;
    known.push_back(exts + " (" + name + ")");
  }
  return common::InvalidArgumentError("cannot import '" + options.path + "': expected " +
                                      JoinNames(known));
}

}  // namespace

Result<std::vector<std::string>> ExportMap(const MapStore& store, const ProfileDeriver* deriver,
                                           const ExportOptions& options,
                                           const io::FormatRegistry& formats) {
  auto info = store.GetMapInfo(options.ref);
  if (!info.ok()) return info.status();
  const io::ExportFormat* format = formats.FindExporter(options.format);
  if (format == nullptr) {
    return common::InvalidArgumentError("unknown export format '" + options.format + "' (" +
                                        JoinNames(formats.ExportNames()) + ")");
  }
  const io::ExportContext ctx(store, deriver, std::move(info).value(), options);
  return format->write(ctx);
}

Result<MapInfo> ImportMap(MapStore& store, const ImportOptions& options, const WriteContext& ctx,
                          const io::FormatRegistry& formats) {
  Status s = ValidateName("site name", options.site);
  if (!s.ok()) return s;
  if (!(s = ValidateName("map name", options.name)).ok()) return s;
  auto format = ImporterOf(options, formats);
  if (!format.ok()) return format.status();
  // The latest version, if any, is where the new one may start.
  auto latest = store.GetMapInfo({options.site, options.name, 0});
  if (!latest.ok() && latest.status().code() != common::StatusCode::kNotFound) {
    return latest.status();
  }
  io::ImportTarget target(store, options,
                          latest.ok() ? std::optional<MapInfo>(*latest) : std::nullopt);
  MapSnapshot& snapshot = target.snapshot();
  snapshot.site = options.site;
  snapshot.name = options.name;
  snapshot.provenance = options.provenance;
  if (snapshot.provenance.code_version.empty()) {
    snapshot.provenance.code_version = "import " + fs::path(options.path).filename().string();
  }
  if (!(s = (*format)->read(options.path, target)).ok()) return s;
  return store.SaveMap(snapshot, ctx);
}

}  // namespace cairn::mapstore
