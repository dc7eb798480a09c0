// Command line shared by the Node.js baselines of the Type A benchmark:
//   SESSION.csv [--threads N] [--json OUT.json]
// Returns {path, threads, jsonPath}; prints the usage and exits 2 when it does not parse.
export function parseBaselineArgs(script) {
  const args = process.argv.slice(2);
  let path = null;
  let threads = 2;
  let jsonPath = null;
  for (let i = 0; i < args.length; ++i) {
    if (args[i] === "--threads") threads = Number(args[++i]);
    else if (args[i] === "--json") jsonPath = args[++i];
    else path = args[i];
  }
  if (!path || !(threads >= 1)) {
    console.error(`usage: ${script} SESSION.csv [--threads N] [--json OUT.json]`);
    process.exit(2);
  }
  return { path, threads, jsonPath };
}
