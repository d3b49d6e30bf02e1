#pragma once

/// @file
/// cairn-map: the map store's command line, working on the database file directly (no bus).
///
///   cairn-map list     maps of every site (latest versions; --all-versions, --deleted)
///   cairn-map show     one map version: provenance, geometry, layers, obstacles, cache, audit
///   cairn-map export   a registered format (mapstore/io/format_registry.h): ROS map_server
///                      YAML + PGM (trinary, scale, raw), PNG with a legend, OctoMap .bt/.ot,
///                      CSV of obstacles; `cairn-map help` lists them
///   cairn-map import   a YAML + PGM map (hand-drawn static maps too), .bt/.ot, .csv
///   cairn-map share    derive a map for another profile and list the verdicts that change
///   cairn-map diff     two versions, or one version under two profiles
///   cairn-map eval     a map against a simulator world's ground truth (mapstore/map_eval.h,
///                      simulator/ground_truth.h): precision, recall, coverage, IoU, walls
///   cairn-map check    integrity: PRAGMA integrity_check, foreign keys, every blob checksum
///   cairn-map vacuum   drop unreferenced blobs and compact the file
///   cairn-map migrate  bring an older schema to the current one
///   cairn-map profiles / put-profile / delete / audit / places
///   cairn-map serve    serve a stored map to a robot on the bus: runs cairn-map-server (the
///                      only command that uses the bus, kept in its own program)
///
/// Every command prints --help. Long operations show progress when stdout is a terminal.
/// Exit status: 0 success, 1 failure (or problems found by check), 2 bad usage.

namespace cairn::mapstore {

/// Runs one command line (argv[0] is the program, argv[1] the command).
int RunMapCli(int argc, char** argv);

}  // namespace cairn::mapstore
