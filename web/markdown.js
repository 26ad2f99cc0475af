// Renders the project's generated reports (docs/*.md) as DOM nodes: headings,
// paragraphs, lists, tables, code blocks, images, links, bold and inline code.
// Only the subset the reports use; text is always inserted as text nodes, so
// nothing in a document can inject markup. Relative links and images resolve
// against `base` (the server's /docs/ path).
"use strict";

window.markdown = (function () {
  function el(tag, attrs, children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
    for (const c of children || []) e.appendChild(typeof c === "string" ? document.createTextNode(c) : c);
    return e;
  }

  const relative = href => !/^([a-z]+:|\/|#)/i.test(href);

  // Inline spans: `code`, **bold**, ![alt](src), [text](href).
  function inline(text, base) {
    const out = [];
    const re = /`([^`]+)`|\*\*(.+?)\*\*|!\[([^\]]*)\]\(([^)\s]+)\)|\[([^\]]+)\]\(([^)\s]+)\)/g;
    let last = 0, m;
    while ((m = re.exec(text))) {
      if (m.index > last) out.push(text.slice(last, m.index));
      if (m[1] !== undefined) out.push(el("code", {}, [m[1]]));
      else if (m[2] !== undefined) out.push(el("strong", {}, inline(m[2], base)));
      else if (m[4] !== undefined) out.push(el("img", { src: relative(m[4]) ? base + m[4] : m[4], alt: m[3] }));
      else {
        const href = m[6];
        const target = /\.md$/.test(href) && relative(href) ? "#/doc/" + href.replace(/\.md$/, "") : (relative(href) ? base + href : href);
        out.push(el("a", { href: target }, inline(m[5], base)));
      }
      last = re.lastIndex;
    }
    if (last < text.length) out.push(text.slice(last));
    return out;
  }

  const cells = line => line.trim().replace(/^\|/, "").replace(/\|$/, "").split("|").map(c => c.trim());

  function render(text, base) {
    const root = el("div", { class: "doc" });
    const lines = text.replace(/\r\n/g, "\n").split("\n");
    let i = 0;
    while (i < lines.length) {
      const line = lines[i];
      if (!line.trim()) { i++; continue; }
      let m;
      if ((m = /^(#{1,4})\s+(.*)$/.exec(line))) {
        root.appendChild(el("h" + Math.min(m[1].length + 1, 5), {}, inline(m[2], base)));
        i++;
      } else if (/^```/.test(line)) {
        const body = [];
        i++;
        while (i < lines.length && !/^```/.test(lines[i])) body.push(lines[i++]);
        i++;
        root.appendChild(el("pre", {}, [body.join("\n")]));
      } else if (/^\|/.test(line) && i + 1 < lines.length && /^\|[\s:|-]+\|?\s*$/.test(lines[i + 1])) {
        const head = cells(line);
        i += 2;
        const rows = [];
        while (i < lines.length && /^\|/.test(lines[i])) rows.push(cells(lines[i++]));
        const table = el("table", { class: "data" }, [
          el("thead", {}, [el("tr", {}, head.map(c => el("th", {}, inline(c, base))))]),
          el("tbody", {}, rows.map(r => el("tr", {}, r.map(c => el("td", {}, inline(c, base)))))),
        ]);
        root.appendChild(el("div", { class: "table-wrap" }, [table]));
      } else if (/^\s*[-*]\s+/.test(line)) {
        const items = [];
        while (i < lines.length && /^\s*[-*]\s+/.test(lines[i])) {
          let item = lines[i++].replace(/^\s*[-*]\s+/, "");
          while (i < lines.length && /^\s{2,}\S/.test(lines[i]) && !/^\s*[-*]\s+/.test(lines[i])) item += " " + lines[i++].trim();
          items.push(el("li", {}, inline(item, base)));
        }
        root.appendChild(el("ul", {}, items));
      } else {
        const para = [];
        while (i < lines.length && lines[i].trim() && !/^(#{1,4}\s|```|\||\s*[-*]\s)/.test(lines[i])) para.push(lines[i++].trim());
        root.appendChild(el("p", {}, inline(para.join(" "), base)));
      }
    }
    return root;
  }

  return { render };
})();
