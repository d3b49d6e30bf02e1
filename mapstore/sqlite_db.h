#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/status.h"

struct sqlite3;
struct sqlite3_stmt;

/// @file
/// A thin RAII layer over the SQLite C API used by SqliteMapStore: every SQL statement goes
/// through Prepare/Bind (no string-built SQL with values), every return code becomes a Status.

namespace cairn::mapstore::sqlite {

/// Maps an SQLite result code to a status: BUSY/LOCKED -> kUnavailable (worth retrying),
/// FULL -> kResourceExhausted, CORRUPT/NOTADB -> kCorrupt, READONLY/PERM -> kPermissionDenied,
/// CONSTRAINT/AUTH -> kInvalidArgument, CANTOPEN -> kNotFound, others -> kInternal. The message
/// carries SQLite's text and, for I/O errors, the system's (strerror of the errno SQLite saw).
common::Status StatusFromCode(int rc, const std::string& what, sqlite3* db = nullptr);

class Database;

/// One prepared statement. Bind indices start at 1, column indices at 0. One made by
/// Database::Prepare goes back to its database's cache when destroyed (reset, bindings
/// cleared), so the same SQL is compiled once per connection.
class Statement {
 public:
  Statement(sqlite3* db, sqlite3_stmt* stmt, Database* owner = nullptr, std::string sql = {})
      : db_(db), stmt_(stmt), owner_(owner), sql_(std::move(sql)) {}
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  Statement(Statement&& o) noexcept
      : db_(o.db_), stmt_(o.stmt_), owner_(o.owner_), sql_(std::move(o.sql_)) {
    o.stmt_ = nullptr;
  }

  Statement& Bind(int index, int64_t value);
  Statement& Bind(int index, int value) { return Bind(index, static_cast<int64_t>(value)); }
  Statement& Bind(int index, double value);
  Statement& Bind(int index, const std::string& text);
  Statement& BindBlob(int index, const void* data, size_t size);
  Statement& BindNull(int index);

  /// Steps once: true with a row, false when done. A failure is kept in status().
  bool Step();
  /// Steps to completion (for statements without rows); returns the status.
  common::Status Run();
  /// Resets for re-use (bindings are kept until re-bound).
  void Reset();
  const common::Status& status() const { return status_; }

  int64_t Int(int column) const;
  double Double(int column) const;  ///< NULL reads as NaN (SQLite stores NaN as NULL)
  std::string Text(int column) const;
  std::string Blob(int column) const;
  bool IsNull(int column) const;

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_;
  Database* owner_;
  std::string sql_;
  common::Status status_;
};

/// One connection.
class Database {
 public:
  /// Opens (creating it when `create`) or fails with a status naming the file. `immutable`
  /// (read-only only) tells SQLite that nobody changes the file while it is open, so it needs
  /// no lock and no shared-memory file beside it: a WAL database in a folder nobody may write.
  static common::Result<std::unique_ptr<Database>> Open(const std::string& path, bool read_only,
                                                        bool create, bool immutable = false);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  sqlite3* raw() { return db_; }
  const std::string& path() const { return path_; }
  /// Runs SQL without parameters (schema, pragmas, transactions).
  common::Status Exec(const std::string& sql);
  /// Prepares one statement, or takes a compiled one of the same SQL from the cache.
  /// @throws std::logic_error on an SQL syntax error (a bug).
  Statement Prepare(const std::string& sql);
  /// Single integer result of a query without parameters (pragmas), or an error.
  common::Result<int64_t> QueryInt(const std::string& sql);
  int64_t LastInsertRowId();
  int Changes();

 private:
  friend class Statement;
  Database(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}
  /// Takes back a statement Prepare made (reset, so it holds no read transaction open).
  void Recycle(std::string sql, sqlite3_stmt* stmt);
  sqlite3* db_;
  std::string path_;
  std::mutex cache_mutex_;
  std::map<std::string, std::vector<sqlite3_stmt*>> cache_;  // idle compiled statements by SQL
  size_t cached_{0};
};

/// BEGIN IMMEDIATE ... COMMIT, rolled back in the destructor unless committed.
class Transaction {
 public:
  explicit Transaction(Database* db) : db_(db) {}
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  /// BEGIN IMMEDIATE (takes the write lock now, so a busy database fails here, not mid-way).
  common::Status Begin();
  common::Status Commit();

 private:
  Database* db_;
  bool open_{false};
};

}  // namespace cairn::mapstore::sqlite
