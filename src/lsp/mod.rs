//! `ctlgraph lsp`: a language server for graph files over stdio, on
//! rust-analyzer's `lsp-server` scaffold. Diagnostics come from the same
//! loader and compiler as `ctlgraph check`; hover, completion, definition
//! and symbols read the document's YAML tree and the block library
//! (`document.rs`).

mod document;
mod text;

pub use document::diagnostics;

use lsp_server::{Connection, ErrorCode, Message, Notification, Request, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, Notification as _, PublishDiagnostics,
};
use lsp_types::request::{Completion, DocumentSymbolRequest, GotoDefinition, HoverRequest, Request as _};
use lsp_types::{
    CompletionOptions, CompletionResponse, DocumentSymbolResponse, GotoDefinitionResponse, HoverProviderCapability,
    OneOf, PublishDiagnosticsParams, ServerCapabilities, TextDocumentSyncCapability, TextDocumentSyncKind, Uri,
};
use std::collections::HashMap;

/// Serves one client on stdin/stdout until it shuts down.
pub fn serve_stdio() -> Result<(), String> {
    let (connection, io) = Connection::stdio();
    serve(&connection)?;
    drop(connection);
    io.join().map_err(|e| format!("the connection: {e}"))
}

/// What the server offers.
fn capabilities() -> ServerCapabilities {
    ServerCapabilities {
        text_document_sync: Some(TextDocumentSyncCapability::Kind(TextDocumentSyncKind::FULL)),
        hover_provider: Some(HoverProviderCapability::Simple(true)),
        completion_provider: Some(CompletionOptions {
            trigger_characters: Some(vec![".".into(), ":".into(), " ".into()]),
            ..CompletionOptions::default()
        }),
        definition_provider: Some(OneOf::Left(true)),
        document_symbol_provider: Some(OneOf::Left(true)),
        ..ServerCapabilities::default()
    }
}

/// The open documents' text as last sent, by URI (as text: a `Uri` caches
/// its parts inside, no key for a map).
type Documents = HashMap<String, String>;

pub fn serve(connection: &Connection) -> Result<(), String> {
    let caps = serde_json::to_value(capabilities()).map_err(|e| e.to_string())?;
    connection.initialize(caps).map_err(|e| format!("initialize: {e}"))?;
    let mut docs = Documents::new();
    for message in &connection.receiver {
        match message {
            Message::Request(req) => {
                if connection.handle_shutdown(&req).map_err(|e| e.to_string())? {
                    return Ok(());
                }
                // A fault in answering one request must not end the session.
                let id = req.id.clone();
                let response = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| respond(&docs, req)))
                    .unwrap_or_else(|_| {
                        Response::new_err(id, ErrorCode::InternalError as i32, "internal error".into())
                    });
                connection.sender.send(Message::Response(response)).map_err(|e| e.to_string())?;
            }
            Message::Notification(note) => {
                if let Some(uri) = update(&mut docs, note) {
                    let text = docs.get(uri.as_str()).map(String::as_str);
                    let diagnose = || text.map(|t| document::diagnostics(&uri, t)).unwrap_or_default();
                    let diagnostics =
                        std::panic::catch_unwind(std::panic::AssertUnwindSafe(diagnose)).unwrap_or_default();
                    let params = PublishDiagnosticsParams { uri, diagnostics, version: None };
                    let note = Notification::new(PublishDiagnostics::METHOD.into(), params);
                    connection.sender.send(Message::Notification(note)).map_err(|e| e.to_string())?;
                }
            }
            Message::Response(_) => {}
        }
    }
    Ok(())
}

/// Applies an open, change or close; returns the document to diagnose.
fn update(docs: &mut Documents, note: Notification) -> Option<Uri> {
    match note.method.as_str() {
        DidOpenTextDocument::METHOD => {
            let p: lsp_types::DidOpenTextDocumentParams = serde_json::from_value(note.params).ok()?;
            let uri = p.text_document.uri;
            docs.insert(uri.as_str().to_string(), p.text_document.text);
            Some(uri)
        }
        DidChangeTextDocument::METHOD => {
            let p: lsp_types::DidChangeTextDocumentParams = serde_json::from_value(note.params).ok()?;
            // Full synchronisation: the last change is the whole text.
            let text = p.content_changes.into_iter().last()?.text;
            let uri = p.text_document.uri;
            docs.insert(uri.as_str().to_string(), text);
            Some(uri)
        }
        DidCloseTextDocument::METHOD => {
            let p: lsp_types::DidCloseTextDocumentParams = serde_json::from_value(note.params).ok()?;
            docs.remove(p.text_document.uri.as_str());
            // Cleared: a closed file shows no diagnostics.
            Some(p.text_document.uri)
        }
        _ => None,
    }
}

/// The response to a request (a null result for a document not open or a
/// place with nothing to say; an error for a method not offered).
fn respond(docs: &Documents, req: Request) -> Response {
    let Request { id, method, params } = req;
    let result = match method.as_str() {
        HoverRequest::METHOD => parse(params).map(|p: lsp_types::HoverParams| {
            let at = p.text_document_position_params;
            let doc = text_of(docs, &at.text_document.uri);
            to_json(doc.and_then(|t| document::hover(&at.text_document.uri, t, at.position)))
        }),
        Completion::METHOD => parse(params).map(|p: lsp_types::CompletionParams| {
            let at = p.text_document_position;
            let doc = text_of(docs, &at.text_document.uri);
            let items = doc.map(|t| document::completion(&at.text_document.uri, t, at.position)).unwrap_or_default();
            to_json(Some(CompletionResponse::Array(items)))
        }),
        GotoDefinition::METHOD => parse(params).map(|p: lsp_types::GotoDefinitionParams| {
            let at = p.text_document_position_params;
            let doc = text_of(docs, &at.text_document.uri);
            let place = doc.and_then(|t| document::definition(&at.text_document.uri, t, at.position));
            to_json(place.map(GotoDefinitionResponse::Scalar))
        }),
        DocumentSymbolRequest::METHOD => parse(params).map(|p: lsp_types::DocumentSymbolParams| {
            to_json(text_of(docs, &p.text_document.uri).map(|t| DocumentSymbolResponse::Nested(document::symbols(t))))
        }),
        _ => return Response::new_err(id, ErrorCode::MethodNotFound as i32, format!("`{method}` is not offered")),
    };
    match result {
        Ok(value) => Response::new_ok(id, value),
        Err(message) => Response::new_err(id, ErrorCode::InvalidParams as i32, message),
    }
}

fn text_of<'a>(docs: &'a Documents, uri: &Uri) -> Option<&'a str> {
    docs.get(uri.as_str()).map(String::as_str)
}

fn parse<P: serde::de::DeserializeOwned>(params: serde_json::Value) -> Result<P, String> {
    serde_json::from_value(params).map_err(|e| e.to_string())
}

/// A result as JSON, `null` for none.
fn to_json<T: serde::Serialize>(value: Option<T>) -> serde_json::Value {
    value.and_then(|v| serde_json::to_value(v).ok()).unwrap_or(serde_json::Value::Null)
}
