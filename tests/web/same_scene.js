// node tests/web/same_scene.js DIR_A DIR_B: the viewer reads the same scene from both exports'
// walkvis.bin and cell files (one deflated, one raw: `walkvis export --raw`): every array of the
// building, the walker's floors and every view cell's tree equal element for element, META equal
// but for what depends on how the bytes are stored (kStoredForm).
// Prints one line; exit status 0 when equal, 1 otherwise.
'use strict';
const { readExport } = require('./read_export.js');

// walkvis.bin's size and the cells' checksums of their stored bytes, which differ by design.
const kStoredForm = new Set(['bytes', 'checksum']);

async function main() {
  const [a, b] = await Promise.all(process.argv.slice(2, 4).map(readExport));
  const differ = [];
  let values = 0;
  const same = (x, y, where) => {
    if (ArrayBuffer.isView(x)) {
      values += x.length;
      if (!ArrayBuffer.isView(y) || x.length !== y.length || x.some((v, i) => !Object.is(v, y[i]))) differ.push(where);
    } else if (x && typeof x === 'object') {
      const keys = new Set([...Object.keys(x), ...Object.keys(y || {})]);
      for (const k of keys) if (!kStoredForm.has(k)) same(x[k], y ? y[k] : undefined, where + '.' + k);
    } else if (!Object.is(x, y)) {
      differ.push(where);
    }
  };
  same(a, b, 'scene');
  console.log('same scene: ' + values + ' array values compared, ' + differ.length + ' differences' +
              (differ.length ? ' (' + differ.slice(0, 5).join(', ') + ')' : '') + '; ' + a.bytes + ' against ' + b.bytes + ' bytes');
  process.exit(differ.length === 0 ? 0 : 1);
}

main().catch((e) => {
  console.log('same scene: ' + e.message);
  process.exit(1);
});
