// Checks that a baseline computed the numbers metro reports: for every tag and every
// quantity in both, n equal, and the mean and the sample variance equal to rounding.
//
// Usage: node bench/type_a/check.mjs METRO_REPORT.json NAME=BASELINE.json [NAME=...]
//   (BASELINE.json as written by duckdb_baseline.mjs / polars_baseline.mjs --json)
// Prints one "check:" line per baseline and a few sample figures; exits 1 on a mismatch.
//
// Tolerances: the mean to 1e-9 of (|mean| + std), the variance to 1e-9 relative (for a
// constant column, of mean^2 * 2^-52). Both sides sum about 360,000 doubles per tag, in
// different orders and by different algorithms (metro: two-pass, corrected; the baselines:
// their own, DuckDB's in parallel), so they agree to about 1e-13, far inside these bounds,
// while a wrong divisor (n instead of n - 1: 3e-6 relative here) or a lost row fails.
import { readFileSync } from "node:fs";

const [reportPath, ...baselines] = process.argv.slice(2);
if (!reportPath || baselines.length === 0) {
  console.error("usage: check.mjs METRO_REPORT.json NAME=BASELINE.json [NAME=...]");
  process.exit(2);
}
const report = JSON.parse(readFileSync(reportPath, "utf8"));

let failed = false;
for (const spec of baselines) {
  const eq = spec.indexOf("=");
  const name = spec.slice(0, eq);
  const other = JSON.parse(readFileSync(spec.slice(eq + 1), "utf8"));
  let compared = 0;
  let maxMean = 0;
  let maxVariance = 0;
  const problems = [];
  const samples = [];
  for (const tag of report.sensors) {
    const theirs = other[String(tag.sensor)];
    if (!theirs) {
      problems.push(`tag ${tag.sensor} missing`);
      continue;
    }
    for (const [quantity, q] of Object.entries(tag.quantities)) {
      const a = q.type_a;
      const b = theirs[quantity];
      if (!a || !b || q.origin !== "file") continue;  // derived quantities: metro only
      ++compared;
      const dMean = Math.abs(a.mean - b.mean) / Math.max(Math.abs(a.mean) + a.std, 1e-300);
      // A constant column (temp_c here) has variance 0: compare with the rounding of its
      // square, mean^2 * 2^-52, instead.
      const dVariance = Math.abs(a.variance - b.variance) /
                        Math.max(a.variance, a.mean * a.mean * 2 ** -52, 1e-300);
      maxMean = Math.max(maxMean, dMean);
      maxVariance = Math.max(maxVariance, dVariance);
      if (a.n !== b.n) problems.push(`tag ${tag.sensor} ${quantity}: n ${a.n} vs ${b.n}`);
      if (!(dMean <= 1e-9)) problems.push(`tag ${tag.sensor} ${quantity}: mean ${a.mean} vs ${b.mean}`);
      if (!(dVariance <= 1e-9)) {
        problems.push(`tag ${tag.sensor} ${quantity}: variance ${a.variance} vs ${b.variance}`);
      }
      if (samples.length < 3 && (quantity === "gx_dps" || quantity === "az_g")) {
        samples.push(`tag ${tag.sensor} ${quantity} mean ${a.mean.toPrecision(12)} / ` +
                     `${b.mean.toPrecision(12)}, variance ${a.variance.toPrecision(12)} / ` +
                     `${b.variance.toPrecision(12)}`);
      }
    }
  }
  if (compared === 0) problems.push("no quantity in common");
  const ok = problems.length === 0;
  failed ||= !ok;
  console.log(`check: ${name} vs metro: ${report.sensors.length} tags, ${compared} quantities ` +
              `(n, mean, variance), max |d mean| / (|mean| + s) ${maxMean.toExponential(1)}, ` +
              `max |d variance| / variance ${maxVariance.toExponential(1)}: ` +
              `${ok ? "OK" : "MISMATCH"}`);
  for (const s of samples) console.log(`  ${s}  (metro / ${name})`);
  for (const p of problems.slice(0, 10)) console.log(`  ${p}`);
}
process.exit(failed ? 1 : 0);
