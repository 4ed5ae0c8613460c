//! CSV files read by column name (the header row), never by position, so a new or reordered
//! column cannot make a test read the wrong numbers. Quoted fields (`"a, b"`, `""` for a quote)
//! are understood.
use std::path::Path;

pub struct Csv {
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

/// One row, its cells addressed by column name.
pub struct Row<'a> {
    csv: &'a Csv,
    pub cells: &'a [String],
}

impl Csv {
    /// Reads and parses `path`; panics naming the file when it is missing or malformed.
    pub fn read(path: &Path) -> Csv {
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
        Csv::parse(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// Every row must have as many cells as the header.
    pub fn parse(text: &str) -> Result<Csv, String> {
        let mut lines = text.lines().enumerate();
        let header = split(lines.next().ok_or("empty file")?.1)?;
        let rows = lines
            .map(|(i, line)| {
                let cells = split(line).map_err(|e| format!("line {}: {e}", i + 1))?;
                if cells.len() != header.len() {
                    return Err(format!("line {}: {} cells under {} columns: {line:?}", i + 1, cells.len(), header.len()));
                }
                Ok(cells)
            })
            .collect::<Result<_, _>>()?;
        Ok(Csv { header, rows })
    }

    /// Index of column `name`; panics listing the header when there is none.
    pub fn column(&self, name: &str) -> usize {
        self.header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name:?} in {:?}", self.header))
    }

    pub fn rows(&self) -> impl Iterator<Item = Row<'_>> {
        self.rows.iter().map(move |cells| Row { csv: self, cells })
    }
}

impl Row<'_> {
    pub fn get(&self, column: &str) -> &str {
        &self.cells[self.csv.column(column)]
    }

    /// The cell as a number; panics naming the column and the row when it is not one.
    pub fn num(&self, column: &str) -> f64 {
        let cell = self.get(column);
        cell.parse().unwrap_or_else(|_| panic!("{column} = {cell:?} is not a number (row {:?})", self.cells))
    }
}

/// Splits one line into fields.
fn split(line: &str) -> Result<Vec<String>, String> {
    let mut fields = vec![String::new()];
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        let field = fields.last_mut().unwrap();
        match (c, quoted) {
            ('"', false) if field.is_empty() => quoted = true,
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                field.push('"');
            }
            ('"', true) => quoted = false,
            (',', false) => fields.push(String::new()),
            _ => field.push(c),
        }
    }
    if quoted {
        return Err(format!("unterminated quote in {line:?}"));
    }
    Ok(fields)
}
