// The registry's schema, one list of statements per version (docs/registry.md "Schema"). A
// database at version v is migrated by running the lists v+1 .. kRegistrySchemaVersion in one
// transaction, each list ending by setting schema_version.
#pragma once

#include <string>
#include <vector>

#include "sql_backend.hpp"

namespace metro::registry_internal {

// The statements that take a database from version - 1 to `version` (1: creates everything,
// schema_version included).
std::vector<std::string> MigrationTo(int version, const SqlBackend& db);

// The tables a registry of `version` has (schema_version included), sorted.
std::vector<std::string> TablesOf(int version);

// What the database at `url` is, read without writing anything: 0 for an empty database
// (no tables: a new registry), else the version of a metro registry, 1 ..
// kRegistrySchemaVersion. Errors (input errors naming `url`, the value found and what is
// expected): tables but no schema_version (not a metro registry: a foreign database is never
// changed); schema_version not holding exactly one row with a whole number from 1 to
// kRegistrySchemaVersion ('abc', -1, 99999999999, two rows, NULL); a version newer than this
// program; a table of its version missing.
Result<int> ReadSchemaVersion(SqlBackend* db, const std::string& url);

// Brings the database to `target` (1 .. kRegistrySchemaVersion) in one transaction holding
// the write lock (retried, at most 200 times, while other writers hold it): an empty database
// gets the schema, a known older version the migrations after it; a version at or past
// `target` is left unchanged. Returns the version it is at. Errors: those of
// ReadSchemaVersion, a statement that fails (nothing of the transaction stays).
Result<int> Migrate(SqlBackend* db, int target, const std::string& url);

}  // namespace metro::registry_internal
