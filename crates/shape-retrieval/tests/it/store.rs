//! JSON storage of vocabularies and indexes: bit-identical round trips and every refusal.

use crate::common;

use common::{small_collection, small_settings};
use shape_retrieval::model::RetrievalIndex;
use shape_retrieval::store::{IndexStore, JsonFile, VocabularyStore};
use shape_retrieval::RetrievalError;

fn index() -> RetrievalIndex {
    RetrievalIndex::build(&small_collection(), &small_settings(), None).unwrap()
}

#[test]
fn index_and_vocabulary_round_trip_bit_identically() {
    let dir = tempfile::tempdir().unwrap();
    let index = index();
    let file = JsonFile::new(dir.path().join("index.json"));
    file.save_index(&index).unwrap();
    let back = file.load_index().unwrap();
    assert_eq!(back.entries(), index.entries());
    assert_eq!(back.bags(), index.bags());
    assert_eq!(back.vocabulary().descriptor(), index.vocabulary().descriptor());
    assert_eq!(back.vocabulary().standardizer(), index.vocabulary().standardizer());
    let (a, b) = (back.vocabulary().vocabulary(), index.vocabulary().vocabulary());
    assert_eq!(a.sigma(), b.sigma());
    assert_eq!(a.words(), b.words());
    let vfile = JsonFile::new(dir.path().join("vocab.json"));
    vfile.save_vocabulary(index.vocabulary()).unwrap();
    let v = vfile.load_vocabulary().unwrap();
    assert_eq!(v.vocabulary().words(), b.words());
    assert_eq!(v.info(), index.vocabulary().info());
    // Queries against the reloaded index are identical.
    for e in index.entries() {
        assert_eq!(back.rank(&e.signature).unwrap(), index.rank(&e.signature).unwrap());
    }
}

/// Saves the index, edits its JSON text with `edit`, and loads it back.
fn load_edited(edit: impl Fn(&mut serde_json::Value)) -> Result<RetrievalIndex, RetrievalError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.json");
    JsonFile::new(&path).save_index(&index()).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut value);
    std::fs::write(&path, serde_json::to_string(&value).unwrap()).unwrap();
    JsonFile::new(&path).load_index()
}

#[test]
fn bad_files_are_refused_with_the_culprit_named() {
    let dir = tempfile::tempdir().unwrap();
    let missing = JsonFile::new(dir.path().join("none.json"));
    assert!(matches!(missing.load_index(), Err(RetrievalError::Storage { .. })));
    let text = dir.path().join("mesh.off");
    std::fs::write(&text, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
    let err = JsonFile::new(&text).load_index().unwrap_err();
    assert!(
        matches!(err, RetrievalError::Storage { .. }) && err.to_string().contains("mesh.off"),
        "{err}"
    );
    // A vocabulary file is not an index, and the other way round.
    let vocab = dir.path().join("vocab.json");
    JsonFile::new(&vocab).save_vocabulary(index().vocabulary()).unwrap();
    let err = JsonFile::new(&vocab).load_index().unwrap_err();
    assert!(err.to_string().contains("not a wfem-retrieval-index file"), "{err}");

    let storage = |e: Result<RetrievalIndex, RetrievalError>| matches!(e, Err(RetrievalError::Storage { .. }));
    let invalid = |e: &Result<RetrievalIndex, RetrievalError>| matches!(e, Err(RetrievalError::InvalidModel { .. }));
    assert!(storage(load_edited(|v| v["version"] = 99.into())));
    assert!(storage(load_edited(|v| v["surprise"] = 1.into())));
    assert!(storage(load_edited(|v| v["bags"]["distance"] = "cosine".into())));
    // Bags of 1e308 would sum to ∞: refused, and the message prints the value, not `inf`.
    let e = load_edited(|v| v["entries"][1]["bag"][0] = serde_json::json!(1e308));
    assert!(invalid(&e), "{e:?}");
    let msg = e.unwrap_err().to_string();
    assert!(
        msg.contains("entry 1") && msg.contains("1e308") && !msg.contains("inf"),
        "{msg}"
    );
    // A word of another dimension, a non-positive σ, z-score statistics of the wrong length.
    assert!(invalid(&load_edited(|v| {
        v["vocabulary"]["words"][3].as_array_mut().unwrap().push(0.0.into());
    })));
    assert!(invalid(&load_edited(|v| v["vocabulary"]["sigma"] = (-1.0).into())));
    assert!(invalid(&load_edited(|v| {
        v["vocabulary"]["standardizer"]["mean"].as_array_mut().unwrap().pop();
    })));
    assert!(invalid(&load_edited(|v| {
        v["vocabulary"]["descriptor"]["eigenpairs"] = 0.into();
    })));
    // A bag of the wrong length.
    assert!(invalid(&load_edited(|v| {
        v["entries"][0]["bag"].as_array_mut().unwrap().pop();
    })));
}

#[test]
fn numbers_out_of_range_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.json");
    JsonFile::new(&path).save_index(&index()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    // Replace the first bag value by 1e999, which no f64 holds.
    let at = text.find("\"bag\": [").unwrap() + "\"bag\": [".len();
    let end = at + text[at..].find(',').unwrap();
    let edited = format!("{}\n 1e999{}", &text[..at], &text[end..]);
    std::fs::write(&path, edited).unwrap();
    assert!(matches!(
        JsonFile::new(&path).load_index(),
        Err(RetrievalError::Storage { .. })
    ));
}
