// Unit test of the viewer's world links (web/src/world.js): a view or steer link never carries
// the server's own token, a steer link carries the world's token in its fragment only, and a
// steer link's token is moved out of the address bar. No browser, no server: a stand-in window.
import { test } from 'node:test';
import assert from 'node:assert/strict';

function standInWindow(href) {
  const storage = new Map();
  const url = new URL(href);
  globalThis.window = {
    location: { get href() { return url.href; }, get search() { return url.search; }, get hash() { return url.hash; } },
    localStorage: { getItem: (k) => storage.get(k) ?? null, setItem: (k, v) => storage.set(k, v) },
    history: { state: null, replaceState: (_s, _t, next) => { url.href = next; } },
  };
  return storage;
}

const world = await import('../../web/src/world.js');

test('a steer link moves its token into storage and out of the address bar', () => {
  const storage = standInWindow('http://127.0.0.1:8080/?world=lab-1#token=abc123');
  assert.equal(world.currentWorld(), 'lab-1');
  assert.ok(world.adoptTokenFromFragment());
  assert.equal(window.location.href, 'http://127.0.0.1:8080/?world=lab-1');
  assert.equal(storage.get('tumble.world-token.lab-1'), 'abc123');
  assert.equal(world.worldToken('lab-1'), 'abc123');
});

test('shared links leave the server token behind; only the world token travels, in the fragment', () => {
  standInWindow('http://127.0.0.1:8080/?world=lab-1&token=server-secret');
  world.storeWorldToken('lab-1', 'w0rld');
  const view = world.shareable(world.viewLink('lab-1'));
  const steer = world.shareable(world.steerLink('lab-1'));
  assert.equal(view, 'http://127.0.0.1:8080/?world=lab-1');
  assert.equal(steer, 'http://127.0.0.1:8080/?world=lab-1#token=w0rld');
  assert.ok(!view.includes('server-secret') && !steer.includes('server-secret'));
  assert.equal(world.shareable(world.steerLink('other')), null, 'no token held: no steer link');
  // Navigation keeps the server token (a --token-reads server needs it on every request).
  assert.match(world.worldUrl('lab-2'), /token=server-secret/);
});

test('world ids: what the server accepts, and random ids fit', () => {
  standInWindow('http://127.0.0.1:8080/');
  assert.equal(world.currentWorld(), null);
  for (const id of ['a', 'lab-1', 'x'.repeat(64)]) assert.ok(world.isWorldId(id), id);
  for (const id of ['', 'Lab', 'a_b', 'x'.repeat(65), 'a/b']) assert.ok(!world.isWorldId(id), id);
  for (let i = 0; i < 50; i++) assert.ok(world.isWorldId(world.randomWorldId()));
});
