// brdfz.gpu's WebGL2 harness (webgl_backend.py loads it into a blank page of headless Chromium): the
// GLSL ES 3.00 translations of bindings/gpu/shaders/webgl.slang run over a full-viewport triangle,
// one pair or draw per pixel, into RGBA32F render targets read back with readPixels. Arrays cross to
// Python as base64, as page.evaluate passes JSON.
"use strict";

const brdfz = (() => {
  const UNITS = { brdfz_data: 0, brdfz_desc_words: 1, pair_a: 2, pair_b: 3 };  // webgl.slang's bindings
  let gl = null;
  const programs = {};
  const material = [];

  function decode(base64) {
    const text = atob(base64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; ++i) bytes[i] = text.charCodeAt(i);
    return bytes.buffer;
  }

  function encode(bytes) {
    let text = "";
    // String.fromCharCode takes its arguments on the stack: in slices.
    for (let i = 0; i < bytes.length; i += 0x8000) text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    return btoa(text);
  }

  function check(what) {
    if (gl.isContextLost()) throw new Error(`WebGL context lost (${what})`);
    const e = gl.getError();
    if (e !== gl.NO_ERROR) throw new Error(`WebGL error 0x${e.toString(16)} (${what})`);
  }

  function shader(type, source, name) {
    const s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(`${name} does not compile: ${gl.getShaderInfoLog(s)}`);
    return s;
  }

  // A texture of `rows` rows of `width` texels, sampled by texelFetch only (NEAREST: integer and
  // float32 textures are not filterable).
  function texture(internal, format, type, width, rows, data) {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.texImage2D(gl.TEXTURE_2D, 0, internal, width, rows, 0, format, type, data);
    return t;
  }

  // Compiles the entry points ({vertex, fragments: {entry: source}}); returns the renderer's name.
  function init(shaders) {
    gl = document.createElement("canvas").getContext("webgl2", { antialias: false, depth: false, stencil: false });
    if (!gl) throw new Error("unavailable: no WebGL2 context");
    if (!gl.getExtension("EXT_color_buffer_float")) throw new Error("unavailable: WebGL2 without EXT_color_buffer_float (float render targets)");
    const probe = texture(gl.RGBA32F, gl.RGBA, gl.FLOAT, 1, 1, null), probeTarget = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, probeTarget);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, probe, 0);
    const complete = gl.checkFramebufferStatus(gl.FRAMEBUFFER) === gl.FRAMEBUFFER_COMPLETE;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.deleteFramebuffer(probeTarget);
    gl.deleteTexture(probe);
    if (!complete) throw new Error("unavailable: RGBA32F render targets are incomplete");
    const vertex = shader(gl.VERTEX_SHADER, shaders.vertex, "webgl_vertex");
    for (const [entry, source] of Object.entries(shaders.fragments)) {
      const p = gl.createProgram();
      gl.attachShader(p, vertex);
      gl.attachShader(p, shader(gl.FRAGMENT_SHADER, source, entry));
      gl.bindAttribLocation(p, 0, "corner_0");
      gl.linkProgram(p);
      if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`${entry} does not link: ${gl.getProgramInfoLog(p)}`);
      gl.useProgram(p);
      // Samplers by name, less the suffix Slang appends: GLSL ES 3.00 has no layout(binding).
      for (let i = 0; i < gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS); ++i) {
        const name = gl.getActiveUniform(p, i).name, unit = UNITS[name.replace(/_\d+$/, "")];
        if (unit === undefined) throw new Error(`${entry}: unknown uniform ${name}`);
        gl.uniform1i(gl.getUniformLocation(p, name), unit);
      }
      programs[entry] = p;
    }
    gl.bindBuffer(gl.ARRAY_BUFFER, gl.createBuffer());
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
    check("init");
    const info = gl.getExtension("WEBGL_debug_renderer_info");
    return info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
  }

  function maxTextureSize() { return gl.getParameter(gl.MAX_TEXTURE_SIZE); }

  // The material's words and its descriptors' (one per row) as R32UI textures on units 0 and 1.
  function bind(data, width, desc, descWidth) {
    for (const t of material.splice(0)) gl.deleteTexture(t);
    const words = new Uint32Array(decode(data)), descWords = new Uint32Array(decode(desc));
    [[words, width], [descWords, descWidth]].forEach(([w, n], unit) => {
      gl.activeTexture(gl.TEXTURE0 + unit);
      material.push(texture(gl.R32UI, gl.RED_INTEGER, gl.UNSIGNED_INT, n, w.length / n, w));
    });
    check("bind");
  }

  // `entry` on inputs a and b (RGBA32F, `width` texels a row, one item each); its `targets` RGBA32F
  // outputs, each as float32 rows of `width` texels, concatenated.
  function run(entry, a, b, width, targets) {
    const values = [a, b].map((x) => new Float32Array(decode(x)));
    const rows = values[0].length / (4 * width);
    const inputs = values.map((v, i) => {
      gl.activeTexture(gl.TEXTURE2 + i);
      return texture(gl.RGBA32F, gl.RGBA, gl.FLOAT, width, rows, v);
    });
    const framebuffer = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
    const outputs = [];
    for (let i = 0; i < targets; ++i) {
      gl.activeTexture(gl.TEXTURE4);
      outputs.push(texture(gl.RGBA32F, gl.RGBA, gl.FLOAT, width, rows, null));
      gl.bindTexture(gl.TEXTURE_2D, null);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0 + i, gl.TEXTURE_2D, outputs[i], 0);
    }
    gl.drawBuffers(outputs.map((_, i) => gl.COLOR_ATTACHMENT0 + i));
    if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE) throw new Error(`${entry}: its render targets are incomplete`);
    gl.useProgram(programs[entry]);
    gl.viewport(0, 0, width, rows);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    const result = new Float32Array(targets * 4 * width * rows);
    for (let i = 0; i < targets; ++i) {
      gl.readBuffer(gl.COLOR_ATTACHMENT0 + i);
      gl.readPixels(0, 0, width, rows, gl.RGBA, gl.FLOAT, result.subarray(i * 4 * width * rows, (i + 1) * 4 * width * rows));
    }
    check(entry);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.deleteFramebuffer(framebuffer);
    for (const t of [...inputs, ...outputs]) gl.deleteTexture(t);
    return encode(new Uint8Array(result.buffer));
  }

  return { init, maxTextureSize, bind, run };
})();
