// Open an HTML report in a fresh browser context where every network
// request is aborted (and recorded): a self-contained report needs none.
// Either `file` (a path, opened as file://) or `html` (served as the one
// page of http://report.invalid/).

const PAGE = 'http://report.invalid/';

export async function openOffline(browser, { file, html }) {
  const ctx = await browser.newContext({ viewport: { width: 1100, height: 900 } });
  const requests = [];
  await ctx.route('**/*', (route) => {
    const url = route.request().url();
    if (file && url === `file://${file}`) return route.continue();
    if (html && url === PAGE) return route.fulfill({ status: 200, contentType: 'text/html', body: html });
    requests.push(url);
    return route.abort();
  });
  const page = await ctx.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('requestfailed', (r) => errors.push(`requestfailed ${r.url()}`));
  await page.goto(file ? `file://${file}` : PAGE);
  return { ctx, page, requests, errors };
}
