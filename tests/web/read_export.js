// The viewer's scene of an export folder, read under Node the way the page reads it: walkvis.bin
// (W.parseExport), then every view cell's file (W.attachCell), for the scripts beside this one.
'use strict';
const fs = require('fs');
const path = require('path');
const W = require(path.join(__dirname, '..', '..', 'walkthrough', 'web', 'viewer.js'));

function arrayBuffer(file) {
  const b = fs.readFileSync(file);
  return b.buffer.slice(b.byteOffset, b.byteOffset + b.length);
}

async function readExport(dir) {
  const scene = await W.parseExport(arrayBuffer(path.join(dir, 'walkvis.bin')), path.join(dir, 'walkvis.bin'));
  for (const c of scene.cells) await W.attachCell(scene, c.index, arrayBuffer(path.join(dir, c.file)));
  return scene;
}

module.exports = { W, readExport };
