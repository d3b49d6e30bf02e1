#include "mapstore/sqlite_db.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <sqlite3.h>

namespace cairn::mapstore::sqlite {

common::Status StatusFromCode(int rc, const std::string& what, sqlite3* db) {
  const int primary = rc & 0xff;
  const std::string text = sqlite3_errstr(rc);
  std::string message = what == text ? what : what + ": " + text;
  if (db != nullptr) {
    const char* detail = sqlite3_errmsg(db);
    if (detail != nullptr && message.find(detail) == std::string::npos) {
      message += std::string(" (") + detail + ")";
    }
    // What the operating system said (ENOSPC, EROFS, EACCES, EIO), when SQLite kept it.
    const int errno_value = sqlite3_system_errno(db);
    if (errno_value != 0 &&
        (primary == SQLITE_IOERR || primary == SQLITE_FULL || primary == SQLITE_CANTOPEN ||
         primary == SQLITE_READONLY || primary == SQLITE_PERM)) {
      message += std::string(" [") + std::strerror(errno_value) + "]";
    }
  }
  switch (primary) {
    case SQLITE_OK:
    case SQLITE_ROW:
    case SQLITE_DONE:
      return common::Status::Ok();
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      return common::UnavailableError(message);
    case SQLITE_FULL:
      return common::ResourceExhaustedError(message);
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      return common::CorruptError(message);
    case SQLITE_CONSTRAINT:
      return common::InvalidArgumentError(message);
    case SQLITE_CANTOPEN:
      return common::NotFoundError(message);
    case SQLITE_READONLY:
    case SQLITE_PERM:
      // The file, its folder or its file system does not let this process write: nothing the
      // caller can change by asking again.
      return common::PermissionDeniedError(message);
    case SQLITE_AUTH:
      return common::InvalidArgumentError(message);
    default:
      return common::InternalError(message);
  }
}

Statement::~Statement() {
  if (stmt_ == nullptr) return;
  if (owner_ != nullptr) {
    owner_->Recycle(std::move(sql_), stmt_);
  } else {
    sqlite3_finalize(stmt_);
  }
}

Statement& Statement::Bind(int index, int64_t value) {
  sqlite3_bind_int64(stmt_, index, value);
  return *this;
}

Statement& Statement::Bind(int index, double value) {
  sqlite3_bind_double(stmt_, index, value);
  return *this;
}

Statement& Statement::Bind(int index, const std::string& text) {
  sqlite3_bind_text(stmt_, index, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT);
  return *this;
}

Statement& Statement::BindBlob(int index, const void* data, size_t size) {
  // A zero-length blob must still be a blob, not NULL.
  static const char kEmpty = 0;
  sqlite3_bind_blob64(stmt_, index, size > 0 ? data : &kEmpty, size, SQLITE_TRANSIENT);
  return *this;
}

Statement& Statement::BindNull(int index) {
  sqlite3_bind_null(stmt_, index);
  return *this;
}

bool Statement::Step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc != SQLITE_DONE) status_ = StatusFromCode(rc, "sqlite step", db_);
  return false;
}

common::Status Statement::Run() {
  while (Step()) {
  }
  return status_;
}

void Statement::Reset() {
  sqlite3_reset(stmt_);
  status_ = common::Status::Ok();
}

int64_t Statement::Int(int column) const { return sqlite3_column_int64(stmt_, column); }

double Statement::Double(int column) const {
  if (sqlite3_column_type(stmt_, column) == SQLITE_NULL) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return sqlite3_column_double(stmt_, column);
}

std::string Statement::Text(int column) const {
  const auto* p = sqlite3_column_text(stmt_, column);
  const int n = sqlite3_column_bytes(stmt_, column);
  return p == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(p), n);
}

std::string Statement::Blob(int column) const {
  const void* p = sqlite3_column_blob(stmt_, column);
  const int n = sqlite3_column_bytes(stmt_, column);
  return p == nullptr ? std::string() : std::string(static_cast<const char*>(p), n);
}

bool Statement::IsNull(int column) const {
  return sqlite3_column_type(stmt_, column) == SQLITE_NULL;
}

namespace {

// A file: URI of a path (RFC 3986 escapes for what a URI gives meaning to).
std::string FileUri(const std::string& path) {
  std::string out = "file:";
  for (unsigned char c : path) {
    if (c == '%' || c == '?' || c == '#' || c < 0x20 || c >= 0x7f) {
      char buf[4];
      std::snprintf(buf, sizeof(buf), "%%%02X", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

}  // namespace

common::Result<std::unique_ptr<Database>> Database::Open(const std::string& path, bool read_only,
                                                         bool create, bool immutable) {
  sqlite3* db = nullptr;
  int flags = read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE;
  if (create && !read_only) flags |= SQLITE_OPEN_CREATE;
  flags |= SQLITE_OPEN_NOMUTEX;  // one connection per store, guarded by the store
  std::string name = path;
  if (immutable && read_only) {
    name = FileUri(path) + "?mode=ro&immutable=1";
    flags |= SQLITE_OPEN_URI;
  }
  const int rc = sqlite3_open_v2(name.c_str(), &db, flags, nullptr);
  if (rc != SQLITE_OK) {
    common::Status s = StatusFromCode(rc, "cannot open database '" + path + "'", db);
    sqlite3_close(db);
    return s;
  }
  sqlite3_extended_result_codes(db, 1);
  return std::unique_ptr<Database>(new Database(db, path));
}

Database::~Database() {
  for (auto& [sql, stmts] : cache_) {
    for (sqlite3_stmt* stmt : stmts) sqlite3_finalize(stmt);
  }
  sqlite3_close_v2(db_);
}

void Database::Recycle(std::string sql, sqlite3_stmt* stmt) {
  // A bounded cache: statements beyond it (SQL built per call) are finalized.
  constexpr size_t kMaxCached = 256;
  sqlite3_reset(stmt);
  sqlite3_clear_bindings(stmt);
  std::lock_guard<std::mutex> lock(cache_mutex_);
  if (cached_ >= kMaxCached) {
    sqlite3_finalize(stmt);
    return;
  }
  cache_[std::move(sql)].push_back(stmt);
  ++cached_;
}

common::Status Database::Exec(const std::string& sql) {
  char* error = nullptr;
  const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error);
  if (rc == SQLITE_OK) return common::Status::Ok();
  std::string what = error != nullptr ? error : "";
  sqlite3_free(error);
  return StatusFromCode(rc, what.empty() ? "sqlite exec" : what, db_);
}

Statement Database::Prepare(const std::string& sql) {
  {
    std::lock_guard<std::mutex> lock(cache_mutex_);
    auto it = cache_.find(sql);
    if (it != cache_.end() && !it->second.empty()) {
      sqlite3_stmt* stmt = it->second.back();
      it->second.pop_back();
      --cached_;
      return Statement(db_, stmt, this, sql);
    }
  }
  sqlite3_stmt* stmt = nullptr;
  const int rc = sqlite3_prepare_v2(db_, sql.c_str(), static_cast<int>(sql.size()), &stmt, nullptr);
  if (rc != SQLITE_OK) {
    // A malformed statement is a bug; a busy or corrupt database is not.
    const int primary = rc & 0xff;
    if (primary == SQLITE_ERROR) {
      throw std::logic_error("bad SQL '" + sql + "': " + sqlite3_errmsg(db_));
    }
    throw std::runtime_error(StatusFromCode(rc, "prepare", db_).ToString());
  }
  return Statement(db_, stmt, this, sql);
}

common::Result<int64_t> Database::QueryInt(const std::string& sql) {
  sqlite3_stmt* stmt = nullptr;
  int rc = sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr);
  if (rc != SQLITE_OK) {
    common::Status s = StatusFromCode(rc, sql, db_);
    sqlite3_finalize(stmt);
    return s;
  }
  rc = sqlite3_step(stmt);
  int64_t value = 0;
  if (rc == SQLITE_ROW) value = sqlite3_column_int64(stmt, 0);
  sqlite3_finalize(stmt);
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) return StatusFromCode(rc, sql, db_);
  return value;
}

int64_t Database::LastInsertRowId() { return sqlite3_last_insert_rowid(db_); }

int Database::Changes() { return sqlite3_changes(db_); }

Transaction::~Transaction() {
  if (open_) db_->Exec("ROLLBACK");
}

common::Status Transaction::Begin() {
  common::Status s = db_->Exec("BEGIN IMMEDIATE");
  open_ = s.ok();
  return s;
}

common::Status Transaction::Commit() {
  common::Status s = db_->Exec("COMMIT");
  if (s.ok()) {
    open_ = false;
  }
  return s;
}

}  // namespace cairn::mapstore::sqlite
