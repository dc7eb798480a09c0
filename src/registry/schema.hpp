// The registry's schema, one list of statements per version (docs/registry.md "Schema"). A
// database at version v is migrated by running the lists v+1 .. kRegistrySchemaVersion, each in
// its own transaction, each ending by setting schema_version.
#pragma once

#include <string>
#include <vector>

#include "sql_backend.hpp"

namespace metro::registry_internal {

// The statements that take a database from version - 1 to `version` (1: creates everything).
std::vector<std::string> MigrationTo(int version, const SqlBackend& db);

// Reads schema_version (0 for an empty database), creating the table when absent. Inside a
// transaction.
Result<int> ReadSchemaVersion(SqlBackend* db);

// Migrates to `target` (<= kRegistrySchemaVersion), one transaction per version, retried
// while other writers hold the lock. Error when the database is newer than `target` allows
// (`refuse_newer`) or a statement fails.
Result<int> Migrate(SqlBackend* db, int target, const std::string& url);

}  // namespace metro::registry_internal
