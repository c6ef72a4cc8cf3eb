//! Writes small glTF files for tests: float accessors packed into one
//! data-URI buffer, the rest of the JSON given as text.

/// Accessors gathered into one buffer; [`GltfBuilder::finish`] adds the
/// caller's nodes, meshes, animations, ... around them.
#[derive(Default)]
pub struct GltfBuilder {
    data: Vec<u8>,
    accessors: Vec<String>,
}

fn components(kind: &str) -> usize {
    match kind {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        "MAT4" => 16,
        _ => panic!("unknown accessor type {kind}"),
    }
}

impl GltfBuilder {
    /// Adds a float accessor of `kind` ("SCALAR", "VEC3", ...) holding
    /// `values`, with its min and max; returns its index.
    pub fn floats(&mut self, values: &[f32], kind: &str) -> usize {
        let n = components(kind);
        assert_eq!(values.len() % n, 0, "{kind} needs multiples of {n}");
        let mut min = vec![f32::INFINITY; n];
        let mut max = vec![f32::NEG_INFINITY; n];
        for (i, v) in values.iter().enumerate() {
            min[i % n] = min[i % n].min(*v);
            max[i % n] = max[i % n].max(*v);
        }
        let offset = self.data.len();
        self.data
            .extend(values.iter().flat_map(|v| v.to_le_bytes()));
        self.accessor(offset, values.len() / n, kind, 5126, &min, &max)
    }

    /// Adds an unsigned-short accessor (JOINTS_0, indices); returns its index.
    pub fn u16s(&mut self, values: &[u16], kind: &str) -> usize {
        let n = components(kind);
        let offset = self.data.len();
        self.data
            .extend(values.iter().flat_map(|v| v.to_le_bytes()));
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        self.accessor(offset, values.len() / n, kind, 5123, &[], &[])
    }

    fn accessor(
        &mut self,
        offset: usize,
        count: usize,
        kind: &str,
        component_type: u32,
        min: &[f32],
        max: &[f32],
    ) -> usize {
        let bounds = if min.is_empty() {
            String::new()
        } else {
            format!(r#", "min": {min:?}, "max": {max:?}"#)
        };
        self.accessors.push(format!(
            r#"{{"bufferView": 0, "byteOffset": {offset}, "componentType": {component_type}, "count": {count}, "type": "{kind}"{bounds}}}"#
        ));
        self.accessors.len() - 1
    }

    /// The file: `body` holds the other top-level properties ("nodes",
    /// "meshes", "animations", ...), comma-separated, without braces.
    pub fn finish(&self, body: &str) -> String {
        format!(
            r#"{{
  "asset": {{"version": "2.0"}},
  {body},
  "accessors": [{}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": {}}}],
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}]
}}"#,
            self.accessors.join(",\n    "),
            self.data.len(),
            self.data.len(),
            base64(&self.data)
        )
    }
}

pub fn base64(data: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in data.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}
