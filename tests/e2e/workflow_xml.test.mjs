// The builder's XML writer (web/ui/workflow.js) in Node: one element per line, each line
// owned by its step, so a validation error's line number finds the step.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { atomicStep, blockStep, toXml, operatorsFor } from '../../web/ui/workflow.js';

test('a while loop and the line owners', () => {
  const smooth = atomicStep({ name: 'LaplacianSmoothing', params: [{ name: 'iterations', default: 1 }] });
  const loop = blockStep('while', { name: 'NumberOfBoundaryLoops', value_type: 'natural' });
  const fill = atomicStep({ name: 'FillHoles', params: [] });
  loop.body.push(fill);
  const { xml, owner } = toXml([smooth, loop]);
  const lines = xml.split('\n');
  assert.equal(lines[2], '<atomic><name>LaplacianSmoothing</name><parameters><parameter name="iterations">1</parameter></parameters></atomic>');
  assert.equal(owner[3], smooth.id);
  assert.equal(owner[4], loop.id);
  assert.equal(lines[5], '<atomic><name>FillHoles</name></atomic>');
  assert.equal(owner[6], fill.id);
});

test('values are escaped and booleans take EQ/NEQ only', () => {
  const s = atomicStep({ name: 'AddNoise', params: [{ name: 'seed', default: '<1&2>' }] });
  assert.match(toXml([s]).xml, /&lt;1&amp;2&gt;/);
  assert.deepEqual(operatorsFor('boolean'), ['EQ', 'NEQ']);
  assert.equal(blockStep('if', { name: 'IsWatertight', value_type: 'boolean' }).cond.value, 'true');
});
