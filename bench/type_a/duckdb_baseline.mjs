// Baseline for the Type A benchmark: DuckDB read_csv + GROUP BY sensor with count, mean
// (avg) and sample variance (var_samp, n - 1) of every column but `sensor`, the work
// pandas_baseline.py does.
//
// Usage: node bench/type_a/duckdb_baseline.mjs SESSION.csv [--threads N] [--json OUT.json]
//   --threads N   DuckDB worker threads (default 2, the benchmark machine's cores)
//   --json FILE   also write {sensor: {column: {n, mean, variance}}} for the check
//                 against metro's report (untimed)
// Prints the seconds spent in-process (read + aggregate), excluding Node start-up, module
// load and opening the in-memory database, in pandas_baseline.py's format.
import { parseBaselineArgs } from "./baseline_args.mjs";
import { writeFileSync } from "node:fs";

import { DuckDBInstance, version } from "@duckdb/node-api";

const { path, threads, jsonPath } = parseBaselineArgs("duckdb_baseline.mjs");

const instance = await DuckDBInstance.create(":memory:", { threads: String(threads) });
const connection = await instance.connect();

const start = performance.now();
// COLUMNS(* EXCLUDE (sensor)) expands to every other column; "\0" is the column's name.
const reader = await connection.runAndReadAll(
  `SELECT sensor, count(*) AS n,
          avg(COLUMNS(* EXCLUDE (sensor))) AS "mean_\\0",
          var_samp(COLUMNS(* EXCLUDE (sensor))) AS "var_\\0"
     FROM read_csv($1, comment = '#', header = true)
    GROUP BY sensor ORDER BY sensor`,
  [path],
);
const rows = reader.getRowObjects();
const elapsed = (performance.now() - start) / 1000;

const total = rows.reduce((sum, r) => sum + Number(r.n), 0);
console.log(
  `duckdb ${version().replace(/^v/, "")}: ${total} rows, ${rows.length} tags, ${elapsed.toFixed(3)} s in-process`,
);

if (jsonPath) {
  const out = {};
  for (const r of rows) {
    const tag = {};
    for (const name of reader.columnNames()) {
      if (!name.startsWith("mean_")) continue;
      const column = name.slice(5);
      tag[column] = { n: Number(r.n), mean: r[name], variance: r[`var_${column}`] };
    }
    out[String(r.sensor)] = tag;
  }
  writeFileSync(jsonPath, JSON.stringify(out));
}
