// Starts real meshflow processes for the browser tests and always stops them.
import { spawn } from 'node:child_process';
import { createInterface } from 'node:readline';

// Runs `meshflow ARGS` and resolves with { process, url } once its first line names its URL.
export function startMeshflow(exe, args, pattern, timeoutMs = 90000) {
  const child = spawn(exe, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  let stderr = '';
  child.stderr.on('data', (d) => { stderr = (stderr + d).slice(-4000); });
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => { child.kill('SIGKILL'); reject(new Error(`meshflow ${args[0]} not ready in ${timeoutMs} ms: ${stderr}`)); }, timeoutMs);
    child.on('exit', (code) => { clearTimeout(timer); reject(new Error(`meshflow ${args[0]} exited (${code}): ${stderr}`)); });
    createInterface({ input: child.stdout }).once('line', (line) => {
      const m = line.match(pattern);
      clearTimeout(timer);
      if (m) resolve({ process: child, url: m[1], stderr: () => stderr });
      else { child.kill('SIGKILL'); reject(new Error(`unexpected first line: ${line}`)); }
    });
  });
}

// SIGTERM, then SIGKILL after a grace period.
export async function stop(child, graceMs = 10000) {
  if (!child || child.exitCode !== null || child.signalCode !== null) return;
  const exited = new Promise((r) => child.once('exit', r));
  child.kill('SIGTERM');
  const timer = setTimeout(() => child.kill('SIGKILL'), graceMs);
  await exited;
  clearTimeout(timer);
}
