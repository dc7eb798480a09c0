// Baseline for the Type A benchmark: Polars read_csv + group_by sensor with count, mean and
// sample variance (var, ddof 1) of every column but `sensor`, the work pandas_baseline.py
// does. The eager read is used: the lazy scan_csv + group_by + collect, with or without
// streaming, took 10-20 % longer on the benchmark file (docs/benchmarks.md).
//
// Usage: node bench/type_a/polars_baseline.mjs SESSION.csv [--threads N] [--json OUT.json]
//   --threads N   size of Polars' thread pool (POLARS_MAX_THREADS; default 2, the
//                 benchmark machine's cores)
//   --json FILE   also write {sensor: {column: {n, mean, variance}}} for the check
//                 against metro's report (untimed)
// Prints the seconds spent in-process (read + aggregate), excluding Node start-up and module
// load, in pandas_baseline.py's format.
import { parseBaselineArgs } from "./baseline_args.mjs";
import { readFileSync, writeFileSync } from "node:fs";
import { createRequire } from "node:module";

const { path, threads, jsonPath } = parseBaselineArgs("polars_baseline.mjs");

// Polars sizes its pool once, from this variable, when the native module first runs.
process.env.POLARS_MAX_THREADS = String(threads);
const { default: pl } = await import("nodejs-polars");
const require = createRequire(import.meta.url);
const polarsVersion = JSON.parse(
  readFileSync(require.resolve("nodejs-polars/package.json"), "utf8"),
).version;

const start = performance.now();
const frame = pl.readCSV(path, { commentPrefix: "#", hasHeader: true });
const columns = frame.columns.filter((c) => c !== "sensor");
const stats = frame
  .groupBy("sensor")
  .agg(
    pl.len().alias("n"),
    ...columns.map((c) => pl.col(c).mean().alias(`mean_${c}`)),
    ...columns.map((c) => pl.col(c).var(1).alias(`var_${c}`)),
  )
  .sort("sensor");
const elapsed = (performance.now() - start) / 1000;

const records = stats.toRecords();
const total = records.reduce((sum, r) => sum + Number(r.n), 0);
console.log(
  `polars ${polarsVersion}: ${total} rows, ${records.length} tags, ${elapsed.toFixed(3)} s in-process`,
);

if (jsonPath) {
  const out = {};
  for (const r of records) {
    const tag = {};
    for (const c of columns) {
      tag[c] = { n: Number(r.n), mean: r[`mean_${c}`], variance: r[`var_${c}`] };
    }
    out[String(r.sensor)] = tag;
  }
  writeFileSync(jsonPath, JSON.stringify(out));
}
