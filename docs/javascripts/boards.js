/* tcbench's leaderboard tables (docs/leaderboards/, made by tcbench.leaderboard.pages): click a
   column header to sort the rows (numbers by their data-value, text alphabetically; again to
   reverse), type in the box above a table to keep the rows holding every word typed. Plain
   JavaScript, no library, nothing fetched. */
(function () {
  "use strict";

  // The number a cell sorts by: its data-value ("" is none), else its text read as a number.
  function numberOf(cell) {
    if (!cell) return NaN;
    var given = cell.getAttribute("data-value");
    var text = given !== null ? given : cell.textContent.trim().replace(/\u2212/g, "-").replace(/\u00d7$/, "");
    if (text === "" || text === "\u2013") return NaN;
    var x = Number(text);
    return isNaN(x) ? NaN : x;
  }

  function textOf(cell) {
    return cell ? cell.textContent.trim().toLowerCase() : "";
  }

  // A header without data-type sorts as numbers when every filled cell of its column is one.
  function isNumeric(th, rows, index) {
    var kind = th.getAttribute("data-type");
    if (kind === "num") return true;
    if (kind === "text") return false;
    return rows.every(function (row) {
      var cell = row.cells[index];
      var text = cell ? cell.textContent.trim() : "";
      return text === "" || text === "\u2013" || !isNaN(numberOf(cell));
    });
  }

  function sortBy(table, th) {
    var body = table.tBodies[0];
    if (!body) return;
    var index = Array.prototype.indexOf.call(th.parentNode.cells, th);
    var rows = Array.prototype.slice.call(body.rows);
    var numeric = isNumeric(th, rows, index);
    var up = th.getAttribute("aria-sort") !== "ascending";
    var keyed = rows.map(function (row, i) {
      var cell = row.cells[index];
      return {row: row, i: i, key: numeric ? numberOf(cell) : textOf(cell)};
    });
    keyed.sort(function (a, b) {
      var aMissing = numeric ? isNaN(a.key) : a.key === "";
      var bMissing = numeric ? isNaN(b.key) : b.key === "";
      if (aMissing !== bMissing) return aMissing ? 1 : -1; // cells without a value last, either way
      var order = 0;
      if (!aMissing) {
        if (numeric) order = a.key < b.key ? -1 : a.key > b.key ? 1 : 0;
        else order = a.key.localeCompare(b.key, undefined, {numeric: true});
      }
      return (up ? order : -order) || a.i - b.i;
    });
    Array.prototype.forEach.call(th.parentNode.cells, function (h) { h.setAttribute("aria-sort", "none"); });
    th.setAttribute("aria-sort", up ? "ascending" : "descending");
    keyed.forEach(function (k) { body.appendChild(k.row); });
  }

  function filterRows(table, input, count) {
    var words = input.value.toLowerCase().split(/\s+/).filter(Boolean);
    var rows = table.tBodies[0] ? Array.prototype.slice.call(table.tBodies[0].rows) : [];
    var shown = 0;
    rows.forEach(function (row) {
      var text = row.textContent.toLowerCase();
      var keep = words.every(function (w) { return text.indexOf(w) >= 0; });
      row.style.display = keep ? "" : "none";
      if (keep) shown += 1;
    });
    if (count) count.textContent = shown + " of " + rows.length + " rows";
  }

  function setUp(root) {
    var tables = root.querySelectorAll(".tcb-board table");
    Array.prototype.forEach.call(tables, function (table) {
      if (table.getAttribute("data-tcb-ready")) return;
      table.setAttribute("data-tcb-ready", "1");
      var head = table.tHead ? table.tHead.rows[0] : null;
      if (head) {
        Array.prototype.forEach.call(head.cells, function (th) {
          th.classList.add("tcb-sortable");
          th.tabIndex = 0;
          if (!th.hasAttribute("aria-sort")) th.setAttribute("aria-sort", "none");
          th.addEventListener("click", function () { sortBy(table, th); });
          th.addEventListener("keydown", function (e) {
            if (e.key === "Enter" || e.key === " ") { e.preventDefault(); sortBy(table, th); }
          });
        });
      }
      var board = table.closest(".tcb-board");
      var input = board ? board.querySelector(".tcb-filter") : null;
      var count = board ? board.querySelector(".tcb-count") : null;
      if (input) {
        input.addEventListener("input", function () { filterRows(table, input, count); });
        if (input.value) filterRows(table, input, count);
      }
    });
  }

  function start() { setUp(document); }
  if (window.document$ && typeof window.document$.subscribe === "function") {
    window.document$.subscribe(start); // Material's instant navigation: every page it loads
  } else if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", start);
  } else {
    start();
  }
})();
