// gangue web page: tabs, one module per calculation, the server's version.

import { getJson } from './js/api.js';
import { initColumn } from './js/column.js';
import { initImpact } from './js/impact.js';
import { initMigration } from './js/migration.js';
import { initSpalling } from './js/spalling.js';
import { initStudy } from './js/study.js';

const TABS = ['impact', 'column', 'migration', 'study', 'spalling'];

function showTab(name) {
  const active = TABS.includes(name) ? name : TABS[0];
  for (const tab of document.querySelectorAll('[role="tab"]')) {
    const selected = tab.dataset.tab === active;
    tab.setAttribute('aria-selected', String(selected));
    tab.tabIndex = selected ? 0 : -1;
  }
  for (const panel of document.querySelectorAll('[role="tabpanel"]')) {
    panel.hidden = panel.dataset.panel !== active;
  }
}

function initTabs() {
  for (const tab of document.querySelectorAll('[role="tab"]')) {
    tab.addEventListener('click', () => {
      history.replaceState(null, '', `#${tab.dataset.tab}`);
      showTab(tab.dataset.tab);
    });
  }
  // Arrow keys move between tabs (WAI-ARIA tabs pattern).
  document.querySelector('[role="tablist"]').addEventListener('keydown', (event) => {
    const step = { ArrowRight: 1, ArrowLeft: -1 }[event.key];
    if (!step) return;
    const current = TABS.indexOf(document.querySelector('[aria-selected="true"]').dataset.tab);
    const next = TABS[(current + step + TABS.length) % TABS.length];
    history.replaceState(null, '', `#${next}`);
    showTab(next);
    document.getElementById(`tab-${next}`).focus();
  });
  window.addEventListener('hashchange', () => showTab(location.hash.slice(1)));
  showTab(location.hash.slice(1));
}

async function showVersion() {
  const health = await getJson('healthz');
  if (health?.version) {
    document.getElementById('server-version').textContent = `server ${health.version}`;
  }
}

initImpact();
initColumn();
initMigration();
initStudy();
initSpalling();
initTabs();
showVersion();
document.body.dataset.ready = 'true';
