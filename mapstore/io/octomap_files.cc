#include "mapstore/io/octomap_files.h"

#include <memory>
#include <sstream>

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include "mapstore/io/files.h"
#include "mapstore/io/format_registry.h"

namespace cairn::mapstore::io {

using common::InvalidArgumentError;
using common::Result;
using common::Status;

namespace {

// The stored tree in the other form (binary <-> full), through an OcTree.
Result<std::string> ConvertOctomap(const OctomapData& octomap, bool binary) {
  std::istringstream in(octomap.bytes);
  std::unique_ptr<octomap::OcTree> tree;
  if (octomap.binary) {
    tree = std::make_unique<octomap::OcTree>(octomap.resolution_m);
    if (!tree->readBinary(in)) return common::CorruptError("the stored OctoMap does not parse");
  } else {
    std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(in));
    auto* as_tree = dynamic_cast<octomap::OcTree*>(any.get());
    if (as_tree == nullptr) return common::CorruptError("the stored OctoMap is not an OcTree");
    any.release();
    tree.reset(as_tree);
  }
  std::ostringstream out;
  const bool ok = binary ? tree->writeBinary(out) : tree->write(out);
  if (!ok) return common::InternalError("OctoMap could not write the tree");
  return out.str();
}

Result<std::vector<std::string>> ExportOctomap(const ExportContext& ctx, bool binary) {
  auto octomap = ctx.Octomap();
  if (!octomap.ok()) return octomap.status();
  auto path = WriteOctomap(ctx.options().folder, ctx.Stem(), *octomap, binary);
  if (!path.ok()) return path.status();
  return std::vector<std::string>{*path};
}

Status ImportOctomap(const std::string& path, ImportTarget& target) {
  Status s = target.StartFromLatest();
  if (!s.ok()) return s;
  auto octomap = ReadOctomap(path);
  if (!octomap.ok()) return octomap.status();
  target.snapshot().octomap = std::move(octomap).value();
  return Status::Ok();
}

}  // namespace

Result<std::string> WriteOctomap(const std::string& folder, const std::string& stem,
                                 const OctomapData& octomap, bool binary) {
  auto path = OutputPath(folder, stem, binary ? ".bt" : ".ot");
  if (!path.ok()) return path.status();
  std::string bytes;
  if (octomap.binary == binary) {
    bytes = octomap.bytes;
  } else {
    auto converted = ConvertOctomap(octomap, binary);
    if (!converted.ok()) return converted.status();
    bytes = std::move(converted).value();
  }
  const Status s = WriteFileAtomically(*path, bytes);
  if (!s.ok()) return s;
  return *path;
}

Result<OctomapData> ReadOctomap(const std::string& path) {
  auto data = ReadFile(path);
  if (!data.ok()) return data.status();
  OctomapData out;
  const bool binary = data->rfind("# Octomap OcTree binary file", 0) == 0;
  const bool full = data->rfind("# Octomap OcTree file", 0) == 0;
  if (!binary && !full) {
    return InvalidArgumentError(path + " is not an OctoMap .bt or .ot file");
  }
  std::istringstream in(*data);
  if (binary) {
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(in)) return InvalidArgumentError(path + ": OctoMap cannot read it");
    out.resolution_m = tree.getResolution();
  } else {
    std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(in));
    if (!tree) return InvalidArgumentError(path + ": OctoMap cannot read it");
    out.resolution_m = tree->getResolution();
  }
  out.binary = binary;
  out.bytes = std::move(data).value();
  return out;
}

void RegisterOctomapFormats(FormatRegistry* registry) {
  registry->AddExporter({"bt", "OctoMap binary tree (.bt)",
                         [](const ExportContext& ctx) { return ExportOctomap(ctx, true); }});
  registry->AddExporter({"ot", "OctoMap full tree (.ot)",
                         [](const ExportContext& ctx) { return ExportOctomap(ctx, false); }});
  registry->AddImporter(
      {"bt", {".bt"}, "OctoMap binary tree into the latest version", ImportOctomap});
  registry->AddImporter(
      {"ot", {".ot"}, "OctoMap full tree into the latest version", ImportOctomap});
}

}  // namespace cairn::mapstore::io
