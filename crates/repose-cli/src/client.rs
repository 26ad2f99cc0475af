//! The HTTP client every command that talks to a server shares, carrying
//! the access token when one is configured.

use anyhow::Context;
use reqwest::header::{HeaderMap, HeaderValue, AUTHORIZATION};

/// The access token for a server that guards changes: the file named by
/// `REPOSE_TOKEN_FILE`, else `REPOSE_TOKEN`.
fn token() -> anyhow::Result<Option<String>> {
    if let Ok(path) = std::env::var("REPOSE_TOKEN_FILE") {
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read the token file {path} (REPOSE_TOKEN_FILE)"))?;
        return Ok(Some(text.trim().to_string()));
    }
    Ok(std::env::var("REPOSE_TOKEN")
        .ok()
        .map(|t| t.trim().to_string()))
}

/// An HTTP client that sends the access token, if there is one, with
/// every request.
pub(crate) fn http() -> anyhow::Result<reqwest::Client> {
    let mut headers = HeaderMap::new();
    if let Some(t) = token()? {
        let mut value = HeaderValue::from_str(&format!("Bearer {t}"))
            .context("the access token has characters a header cannot carry")?;
        value.set_sensitive(true);
        headers.insert(AUTHORIZATION, value);
    }
    Ok(reqwest::Client::builder()
        .default_headers(headers)
        .build()?)
}
