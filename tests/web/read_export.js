// The viewer's scene of an export folder's walkvis.bin, read under Node the way the page reads it
// (W.parseExport), for the scripts beside this one.
'use strict';
const fs = require('fs');
const path = require('path');
const W = require(path.join(__dirname, '..', '..', 'walkthrough', 'web', 'viewer.js'));

function readExport(dir) {
  const file = path.join(dir, 'walkvis.bin');
  const b = fs.readFileSync(file);
  return W.parseExport(b.buffer.slice(b.byteOffset, b.byteOffset + b.length), file);
}

module.exports = { W, readExport };
