//! Bounds on the sizes of a retrieval recipe, shared by the CLI (`wfem retrieval`), Python and
//! every stored index read back (a hand-edited `eigenpairs` would otherwise start an
//! eigensolve of any size): checked before anything is allocated.

use crate::RetrievalError;

/// Eigenpairs per shape (the descriptors need 100–300).
pub const MAX_RETRIEVAL_EIGS: usize = 1000;
/// The vocabulary size (Shape Google: 48 to a few thousand).
pub const MAX_WORDS: usize = 65_536;

/// `eigs` in 1..=[`MAX_RETRIEVAL_EIGS`] and `words` in 1..=[`MAX_WORDS`].
///
/// # Errors
/// [`RetrievalError::InvalidParameter`] naming the size.
pub fn check_sizes(eigs: usize, words: usize) -> Result<(), RetrievalError> {
    if !(1..=MAX_RETRIEVAL_EIGS).contains(&eigs) {
        return Err(RetrievalError::InvalidParameter {
            name: "eigenpairs",
            value: eigs as f64,
            reason: "must be in 1..=1000 (MAX_RETRIEVAL_EIGS) per shape",
        });
    }
    if !(1..=MAX_WORDS).contains(&words) {
        return Err(RetrievalError::InvalidParameter {
            name: "words",
            value: words as f64,
            reason: "must be in 1..=65536 (MAX_WORDS)",
        });
    }
    Ok(())
}
