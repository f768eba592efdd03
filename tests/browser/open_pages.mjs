#!/usr/bin/env node
// Keeps N monitor pages open in headless Chromium for a while, as N people
// watching the rig (the monitor bench's load): each its own browser context.
// Prints each page's updates and frames decoded at the end, as JSON.
//
//   node open_pages.mjs --url http://127.0.0.1:PORT/ --pages 3 --seconds 40
import { chromium } from 'playwright-core';

const CHROMIUM_ARGS = ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--enable-unsafe-swiftshader'];

function option(name, fallback) {
  const at = process.argv.indexOf('--' + name);
  return at > 0 && at + 1 < process.argv.length ? process.argv[at + 1] : fallback;
}

const url = option('url', '');
const pages = Number(option('pages', '3'));
const seconds = Number(option('seconds', '30'));
if (!url || !(pages >= 1) || !(seconds > 0)) {
  console.error('usage: node open_pages.mjs --url URL [--pages 3] [--seconds 30]');
  process.exit(2);
}

// SIGTERM ends the wait below; the pages are read before the browser closes.
const browser = await chromium.launch({
  executablePath: '/usr/bin/chromium', args: CHROMIUM_ARGS, handleSIGTERM: false,
});
try {
  const opened = [];
  for (let i = 0; i < pages; ++i) {
    const page = await (await browser.newContext({ viewport: { width: 1600, height: 1000 } })).newPage();
    // The socket listens before the monitor starts: the page waits for it.
    await page.goto(url, { waitUntil: 'load', timeout: 120000 });
    opened.push(page);
  }
  console.log(`open_pages: ${pages} pages open on ${url}`);
  await new Promise((resolve) => {
    const timer = setTimeout(resolve, seconds * 1000);
    process.on('SIGTERM', () => { clearTimeout(timer); resolve(); });
  });
  const counts = [];
  for (const page of opened) {
    counts.push(await page.evaluate(() => ({
      updates: window.shapesenseMonitor?.updates ?? 0,
      connected: window.shapesenseMonitor?.connected ?? false,
    })).catch((error) => ({ error: String(error) })));
  }
  console.log('open_pages: ' + JSON.stringify(counts));
} finally {
  await browser.close();
}
