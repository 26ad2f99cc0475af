//! Who may do what: a bearer token for everything that changes the store
//! (creating, queueing, cancelling and retrying sweeps), and, on a private
//! server, for reading results too. And, token or not, a change comes
//! from this server's own page or from a program, never from another
//! site's page in the user's browser ([`same_site`]).
//!
//! The server keeps only the SHA-256 digest of its token, compares the
//! digest of the presented one in constant time, and never prints either:
//! `Debug` shows `Token(…)`. Without a token (a server on loopback) every
//! request is allowed; `repose serve` refuses to listen beyond loopback
//! without one unless told to.

use crate::{ApiError, AppState};
use axum::body::HttpBody;
use axum::extract::{Request, State};
use axum::http::{header, Method, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use sha2::{Digest, Sha256};
use std::fmt;
use std::sync::Arc;
use subtle::ConstantTimeEq;

/// Shortest token accepted: 16 characters.
pub const MIN_TOKEN_LEN: usize = 16;

/// The digest of the server's secret token.
#[derive(Clone)]
pub struct Token(Arc<[u8; 32]>);

impl Token {
    /// A token from its secret text (surrounding whitespace, such as a
    /// file's final newline, is not part of it).
    pub fn new(secret: &str) -> Result<Token, String> {
        let secret = secret.trim();
        if secret.chars().count() < MIN_TOKEN_LEN {
            return Err(format!(
                "the access token must have at least {MIN_TOKEN_LEN} characters"
            ));
        }
        if secret.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return Err("the access token must not contain spaces or control characters".into());
        }
        Ok(Token(Arc::new(digest(secret))))
    }

    /// Whether `presented` is the secret, in time independent of where
    /// they differ.
    pub fn matches(&self, presented: &str) -> bool {
        digest(presented).ct_eq(&self.0[..]).into()
    }
}

impl fmt::Debug for Token {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Token(…)")
    }
}

fn digest(text: &str) -> [u8; 32] {
    Sha256::digest(text.as_bytes()).into()
}

/// What a token guards.
#[derive(Debug, Clone, Default)]
pub struct Access {
    /// None: every request is allowed (a loopback server).
    pub token: Option<Token>,
    /// Reading results needs the token too (the page and `/api/health`
    /// stay open, so that a person can load the page and enter it).
    pub private: bool,
}

impl Access {
    fn guards(&self, method: &Method, path: &str) -> bool {
        if !reads(method) {
            return true;
        }
        self.private && path.starts_with("/api/") && path != "/api/health"
    }
}

/// Whether a request only reads.
fn reads(method: &Method) -> bool {
    matches!(*method, Method::GET | Method::HEAD | Method::OPTIONS)
}

/// Middleware against cross-site requests. A page of another site can
/// make the user's browser post to a server on loopback, which has no
/// token: a plain form or a `text/plain` body needs no permission from
/// the server. So a change is refused with 403 when its `Origin` (which
/// browsers send) names another host than the request's own (`Host`, or
/// `X-Forwarded-Host` behind a proxy), and with 415 when it carries a body
/// that is not declared JSON. Programs that send no `Origin` are unaffected.
pub(crate) async fn same_site(req: Request, next: Next) -> Response {
    if reads(req.method()) {
        return next.run(req).await;
    }
    let headers = req.headers();
    if let Some(origin) = headers.get(header::ORIGIN) {
        let host = headers
            .get("x-forwarded-host")
            .or_else(|| headers.get(header::HOST))
            .and_then(|v| v.to_str().ok());
        let from = origin
            .to_str()
            .ok()
            .and_then(|o| o.split_once("://"))
            .map(|(_, a)| a);
        let same = matches!((from, host), (Some(a), Some(h)) if a.eq_ignore_ascii_case(h.trim()));
        if !same {
            return ApiError::field(
                StatusCode::FORBIDDEN,
                "Origin",
                format!(
                    "a change from the page of another site ({}) is refused",
                    origin.to_str().unwrap_or("?")
                ),
            )
            .into_response();
        }
    }
    let has_body = req.body().size_hint().upper() != Some(0);
    let json = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .map(|v| {
            v.split(';')
                .next()
                .unwrap_or("")
                .trim()
                .to_ascii_lowercase()
        })
        .is_some_and(|t| t == "application/json" || t.ends_with("+json"));
    if has_body && !json {
        return ApiError::field(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "Content-Type",
            "a request body is JSON: send it with Content-Type: application/json",
        )
        .into_response();
    }
    next.run(req).await
}

/// Middleware: answers 401 to a guarded request without the right
/// `Authorization: Bearer` header.
pub(crate) async fn check(State(s): State<AppState>, req: Request, next: Next) -> Response {
    let Some(token) = &s.access.token else {
        return next.run(req).await;
    };
    if !s.access.guards(req.method(), req.uri().path()) {
        return next.run(req).await;
    }
    let presented = req
        .headers()
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "));
    match presented {
        Some(p) if token.matches(p.trim()) => next.run(req).await,
        Some(_) => unauthorized("the access token is not this server's"),
        None => unauthorized(
            "this request needs the server's access token (Authorization: Bearer TOKEN)",
        ),
    }
}

fn unauthorized(message: &str) -> Response {
    let mut resp = ApiError::new(StatusCode::UNAUTHORIZED, message).into_response();
    resp.headers_mut().insert(
        header::WWW_AUTHENTICATE,
        header::HeaderValue::from_static("Bearer realm=\"repose\""),
    );
    resp
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_token_matches_only_itself_and_never_shows() {
        let t = Token::new("correct-horse-battery\n").unwrap();
        assert!(t.matches("correct-horse-battery"));
        assert!(!t.matches("correct-horse-batter"));
        assert!(!t.matches(""));
        assert_eq!(format!("{t:?}"), "Token(…)");
        assert!(Token::new("short").unwrap_err().contains("16"));
        assert!(Token::new("with a space in the middle").is_err());
    }

    #[test]
    fn writes_are_guarded_and_reads_only_on_a_private_server() {
        let open = Access {
            token: None,
            private: false,
        };
        let private = Access {
            private: true,
            ..open.clone()
        };
        assert!(open.guards(&Method::POST, "/api/sweeps"));
        assert!(open.guards(&Method::DELETE, "/anything"));
        assert!(!open.guards(&Method::GET, "/api/sweeps"));
        assert!(private.guards(&Method::GET, "/api/sweeps"));
        assert!(!private.guards(&Method::GET, "/api/health"));
        assert!(!private.guards(&Method::GET, "/static/app.js"));
        assert!(!private.guards(&Method::GET, "/"));
    }
}
