// Test-only reader of KTX2 files: ktx-parse (npm), the parser of three.js's
// KTX2Loader and glTF-Transform, independent of dustoptics' writer.
// Usage: node read.mjs FILE.ktx2  -> JSON on stdout: the header fields, the
// Data Format Descriptor, the key/value data (UTF-8 text, final NUL removed),
// each level's bytes (base64), and whether ktx-parse serializes the parsed
// container back to the same bytes.
import { readFileSync } from "node:fs";
import { read, write } from "ktx-parse";

const input = readFileSync(process.argv[2]);
const container = read(new Uint8Array(input.buffer, input.byteOffset, input.byteLength));
const again = write(container, { keepWriter: true });
const keyValue = {};
for (const [key, value] of Object.entries(container.keyValue)) {
  const text = typeof value === "string" ? value : Buffer.from(value).toString("utf8");
  keyValue[key] = text.endsWith("\0") ? text.slice(0, -1) : text;
}
console.log(JSON.stringify({
  vkFormat: container.vkFormat,
  typeSize: container.typeSize,
  pixelWidth: container.pixelWidth,
  pixelHeight: container.pixelHeight,
  pixelDepth: container.pixelDepth,
  layerCount: container.layerCount,
  faceCount: container.faceCount,
  levelCount: container.levelCount,
  supercompressionScheme: container.supercompressionScheme,
  dataFormatDescriptor: container.dataFormatDescriptor,
  keyValue,
  levels: container.levels.map((level) => ({
    data: Buffer.from(level.levelData).toString("base64"),
    uncompressedByteLength: level.uncompressedByteLength,
  })),
  rewriteIdentical: Buffer.compare(Buffer.from(again), input) === 0,
}));
