// Which world the page shows and what it may do there: the `?world=` of the address, the write
// token the page holds for that world (localStorage, keyed by world id), and the view and steer
// links that can be shared. No parameter means the server's default world, addressed by the
// unprefixed routes exactly as before worlds existed.
//
// Why the token travels in the fragment (`#token=…`) of a steer link: the browser never sends
// the fragment to a server, so it stays out of request lines, proxy logs and Referer headers.
// The page moves it into localStorage at once and removes it from the address bar, so it is
// not left in the history either.

/** World ids the server accepts (docs/protocol.md, "Worlds"). */
export const kWorldIdPattern = /^[a-z0-9-]{1,64}$/;
/** Prefix of the localStorage keys holding write tokens; the world id follows. */
const kTokenKeyPrefix = 'tumble.world-token.';
/** Longest token accepted from a link (the server's are 32 hex characters). */
const kMaxTokenLength = 256;

const kAdjectives = ['amber', 'brisk', 'calm', 'dusky', 'eager', 'fuzzy', 'gentle', 'hazel', 'icy',
  'jolly', 'keen', 'lucky', 'mellow', 'nimble', 'olive', 'plucky', 'quiet', 'rusty', 'sunny', 'tidy',
  'umber', 'vivid', 'windy', 'young', 'zesty'];
const kNouns = ['otter', 'falcon', 'maple', 'comet', 'pebble', 'walrus', 'cedar', 'heron', 'lynx',
  'quartz', 'badger', 'tulip', 'meadow', 'ember', 'puffin', 'canyon', 'raven', 'thistle', 'koala',
  'nebula', 'willow', 'marmot', 'glacier', 'orchid', 'bison'];

/** Tokens kept for this page's life when localStorage is unavailable (private mode, disabled). */
const memoryTokens = new Map();

/** The world named by the page's `?world=` (null: the default world; 'default' counts as none). */
export function currentWorld() {
  const id = new URLSearchParams(window.location.search).get('world');
  return id && id !== 'default' ? id : null;
}

/** Whether `id` is a well-formed world id. */
export function isWorldId(id) {
  return typeof id === 'string' && kWorldIdPattern.test(id);
}

/** The write token held for world `id` (null for none); `id` null is the default world. */
export function worldToken(id) {
  const key = kTokenKeyPrefix + (id ?? 'default');
  try {
    const stored = window.localStorage.getItem(key);
    if (stored) return stored;
  } catch {
    // Storage refused: only tokens of this page's life are known.
  }
  return memoryTokens.get(key) ?? null;
}

/** Keeps the write token of world `id` (null: the default world) for later visits. */
export function storeWorldToken(id, token) {
  const key = kTokenKeyPrefix + (id ?? 'default');
  memoryTokens.set(key, token);
  try {
    window.localStorage.setItem(key, token);
  } catch {
    // Kept in memory only: the steer link still carries it.
  }
}

/**
 * Moves a `#token=…` of the address into storage for the current world and removes it from the
 * address bar (history.replaceState: no reload, no history entry). Returns whether one was taken.
 */
export function adoptTokenFromFragment() {
  const fragment = new URLSearchParams(window.location.hash.replace(/^#/, ''));
  const token = fragment.get('token');
  if (token === null) return false;
  fragment.delete('token');
  const url = new URL(window.location.href);
  url.hash = fragment.toString();
  window.history.replaceState(window.history.state, '', url.href);
  if (!token || token.length > kMaxTokenLength || !/^[\x21-\x7e]+$/.test(token)) return false;
  storeWorldToken(currentWorld(), token);
  return true;
}

/** The page's address for world `id` (null: the default world), other parameters kept, no fragment. */
export function worldUrl(id) {
  const url = new URL(window.location.href);
  url.hash = '';
  if (id) url.searchParams.set('world', id);
  else url.searchParams.delete('world');
  return url.href;
}

/** Link that shows world `id` to whoever opens it (no token: they may watch, not steer). */
export function viewLink(id) {
  return worldUrl(id);
}

/** Link that also lets its holder steer world `id` (null when the page holds no token for it). */
export function steerLink(id) {
  const token = worldToken(id);
  if (!token) return null;
  const url = new URL(worldUrl(id));
  url.hash = new URLSearchParams({ token }).toString();
  return url.href;
}

/**
 * `href` without the server's own token (`?token=`, which a page of a `--token` server may carry):
 * a link meant for others must not hand them the server's key. Only a world's token, in the
 * fragment of a steer link, is meant to travel.
 */
export function shareable(href) {
  if (!href) return href;  // no steer link: nothing to share
  const url = new URL(href);
  url.searchParams.delete('token');
  url.searchParams.delete('access_token');
  return url.href;
}

/** A readable random world id such as `plucky-otter-4821` (about 19 bits of chance). */
export function randomWorldId() {
  const r = new Uint32Array(3);
  crypto.getRandomValues(r);
  const pick = (list, x) => list[x % list.length];
  return `${pick(kAdjectives, r[0])}-${pick(kNouns, r[1])}-${String(r[2] % 10000).padStart(4, '0')}`;
}
