//! Content-addressed blobs: the bytes a person gave the project (motion files, song audio, the
//! song's loudness envelope), each kept once under the SHA-256 of its bytes. The manifest
//! refers to blobs by hash only, so thirty minutes of mocap is stored once however many edits
//! (and undo steps) refer to it, and a saved file or a browser store can check each blob
//! against its name.

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// The SHA-256 of a blob's bytes, written as 64 lower-case hex digits.
#[derive(Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct BlobHash(String);

impl BlobHash {
    /// The hash of `bytes`.
    pub fn of(bytes: &[u8]) -> Self {
        let digest = Sha256::digest(bytes);
        let mut hex = String::with_capacity(64);
        for b in digest {
            hex.push_str(&format!("{b:02x}"));
        }
        BlobHash(hex)
    }

    /// Parses a hash written as 64 hex digits; `None` for anything else (so a manifest cannot
    /// name a path outside the blob folder).
    pub fn parse(text: &str) -> Option<Self> {
        (text.len() == 64 && text.bytes().all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))).then(|| BlobHash(text.to_string()))
    }

    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl fmt::Debug for BlobHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "BlobHash({}…)", &self.0[..self.0.len().min(12)])
    }
}

impl fmt::Display for BlobHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// The blobs of a project, by hash. Cloning shares the bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BlobStore {
    blobs: BTreeMap<BlobHash, Arc<[u8]>>,
}

impl BlobStore {
    /// Keeps `bytes` (once: the same bytes again only return their hash).
    pub fn put(&mut self, bytes: &[u8]) -> BlobHash {
        let hash = BlobHash::of(bytes);
        self.blobs.entry(hash.clone()).or_insert_with(|| Arc::from(bytes));
        hash
    }

    /// Keeps bytes already known to have this hash (checked by the caller).
    pub(crate) fn insert_checked(&mut self, hash: BlobHash, bytes: Arc<[u8]>) {
        self.blobs.insert(hash, bytes);
    }

    pub fn get(&self, hash: &BlobHash) -> Option<&Arc<[u8]>> {
        self.blobs.get(hash)
    }

    pub fn contains(&self, hash: &BlobHash) -> bool {
        self.blobs.contains_key(hash)
    }

    pub fn iter(&self) -> impl Iterator<Item = (&BlobHash, &Arc<[u8]>)> {
        self.blobs.iter()
    }

    pub fn len(&self) -> usize {
        self.blobs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.blobs.is_empty()
    }

    /// Total bytes held.
    pub fn size_bytes(&self) -> usize {
        self.blobs.values().map(|b| b.len()).sum()
    }

    /// Drops every blob not in `keep`.
    pub(crate) fn retain(&mut self, keep: &std::collections::BTreeSet<BlobHash>) {
        self.blobs.retain(|h, _| keep.contains(h));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_bytes_same_hash_stored_once() {
        let mut s = BlobStore::default();
        let a = s.put(b"HIERARCHY");
        let b = s.put(b"HIERARCHY");
        assert_eq!(a, b);
        assert_eq!(s.len(), 1);
        // The SHA-256 of "abc" from FIPS 180-2.
        assert_eq!(BlobHash::of(b"abc").as_str(), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
        assert!(BlobHash::parse(a.as_str()).is_some());
        assert!(BlobHash::parse("../manifest.json").is_none());
    }
}
